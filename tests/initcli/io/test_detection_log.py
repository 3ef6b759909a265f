"""The detection log format, version 1: reader, writer, schema, and every bad-input case."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import pytest

from bimkit.errors import InputError
from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import (
    DetectedObject,
    Detections,
    FeatureRecord,
    HypothesesRecord,
    Meta,
    Odom,
    Scan,
    State,
    Truth,
    read_log,
)
from initcli.io.log_writer import write_log
from tests.helpers import SCHEMAS

SCHEMA = json.loads((SCHEMAS / "detection_log.schema.json").read_text())


META = (
    '{"type":"meta","version":1,"frame":"odom","camera":{"fx":615,"fy":615,"cx":320,"cy":240,"width":640,'
    '"height":480},"camera_pose":{"x":0.2,"y":0,"z":1.0,"roll":0,"pitch":0,"yaw":0}}'
)


ODOM = '{"type":"odom","t":0.0,"x":0,"y":0,"yaw":0}'


DET = (
    '{"type":"detections","t":0.2,"pose":{"x":0,"y":0,"yaw":0},'
    '"objects":[{"class":"Door","score":0.9,"bbox":[300,100,340,380],"depth":3.2}]}'
)


def write(tmp_path: Path, *lines: str, name: str = "log.jsonl") -> Path:
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_every_record_type_round_trips_and_validates(tmp_path: Path) -> None:
    records = [
        Meta(DEFAULT_CAMERA, DEFAULT_MOUNT, depth_window=2, source="unit test"),
        Odom(0.0, 0.0, 0.0, 0.0),
        Detections(
            0.2, Pose2D(0.1, 0.0, 0.01), (DetectedObject("door", 0.87, (1.0, 2.0, 30.0, 200.0), 2.5),)
        ),
        Detections(
            0.3, Pose2D(0.1, 0.0, 0.01), (DetectedObject("lift", 0.6, (1.0, 2.0, 30.0, 200.0), None),)
        ),
        FeatureRecord(0.4, "stairs", 3.0, -1.0),
        Scan(0.5, -1.5, 0.01, 20.0, (1.0, math.nan, 2.5)),
        Truth(0.5, 10.0, 4.0, 1.2),
        State(0.6, {"state": "explore", "target": [1, 2]}),
        HypothesesRecord(0.7, {"verdict": "2 hypotheses"}),
    ]
    path = tmp_path / "all.jsonl"
    write_log(path, records)
    for line in path.read_text().splitlines():
        jsonschema.validate(json.loads(line), SCHEMA)
    log = read_log(path)
    assert log.meta == records[0]
    assert log.records[:4] == records[1:5]
    scan = log.records[4]
    assert isinstance(scan, Scan) and math.isnan(scan.ranges[1]) and scan.ranges[2] == 2.5
    assert log.records[5:] == records[6:]
    assert log.records[6].data == {"state": "explore", "target": [1, 2], "t": 0.6}
    assert log.warnings == [] and log.skipped_bad == 0


def test_hand_written_log_with_unknown_types_and_extra_keys(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        META[:-1] + ',"depth_window":3,"source":"rosbag","future_key":1}',
        ODOM,
        '{"type":"imu","t":0.1,"ax":0}',
        DET,
        '{"type":"imu","t":0.3,"ax":0}',
        '{"type":"wifi","t":0.35}',
        '{"type":"feature","t":0.4,"class":"elevator","x":1.5,"y":2.0,"extra":"ignored"}',
        "",
        '{"type":"truth","t":0.5,"x":1,"y":2,"yaw":0.5}',
    )
    log = read_log(path)
    assert log.meta.depth_window == 3 and log.meta.source == "rosbag"
    assert [type(r).__name__ for r in log.records] == ["Odom", "Detections", "FeatureRecord", "Truth"]
    assert log.lines == [2, 4, 7, 9]
    assert log.skipped_unknown == {"imu": 2, "wifi": 1}
    assert len(log.warnings) == 1 and "unknown type" in log.warnings[0] and "'imu' x2" in log.warnings[0]


@pytest.mark.parametrize(
    ("lines", "expected"),
    [
        ((META, ODOM, '{"type":"odom","t":0.1,"x":0,"y":0'), r"log.jsonl:3: not valid JSON"),
        ((META, '{"type":"odom","x":0,"y":0,"yaw":0}'), r"log.jsonl:2: missing field 't'"),
        ((META, '{"type":"odom","t":"0.1","x":0,"y":0,"yaw":0}'), r"log.jsonl:2: field 't' must be a number"),
        ((META, '{"type":"odom","t":true,"x":0,"y":0,"yaw":0}'), r"log.jsonl:2: field 't' must be a number"),
        ((META, '{"type":"odom","t":NaN,"x":0,"y":0,"yaw":0}'), r"log.jsonl:2: field 't' must be finite"),
        ((META, "[1, 2]"), r"log.jsonl:2: expected a JSON object"),
        ((META, '{"t":1}'), r"log.jsonl:2: missing field 'type'"),
        (
            (META, DET.replace("[300,100,340,380]", "[300,100,340]")),
            r"log.jsonl:2: field objects\[0\]\.'bbox'",
        ),
        ((META, DET.replace("[300,100,340,380]", "[340,100,300,380]")), r"u1 <= u2"),
        ((META, DET.replace('"class":"Door",', "")), r"log.jsonl:2: missing field objects\[0\]\.'class'"),
        (
            (META, DET.replace('"depth":3.2', '"depth":-3.2')),
            r"log.jsonl:2: field objects\[0\]\.'depth': -3.2 m is negative",
        ),
        (
            (META, DET.replace('"score":0.9', '"score":1e9')),
            r"log.jsonl:2: field objects\[0\]\.'score': 1e\+09 is outside \[0, 1\]",
        ),
        ((META, DET.replace('"score":0.9', '"score":-0.1')), r"'score': -0.1 is outside \[0, 1\]"),
        (
            (META, DET.replace('"objects":[', '"objects":{"a":').replace("]}", "}}")),
            r"'objects' must be a list",
        ),
        (
            (META, DET.replace('"pose":{"x":0,"y":0,"yaw":0}', '"pose":{"x":0,"y":0}')),
            r"missing field pose\.'yaw'",
        ),
        ((META, META), r"log.jsonl:2: a second meta record"),
        ((META, ODOM.replace('"t":', '"t":3,"t":')), r"log.jsonl:2: duplicate key 't'"),
        (
            (META, ODOM, ODOM.replace('"x":0', '"x":1'), ODOM.replace('"x":0', '"x":2')),
            r"log.jsonl: all 3 records carry the one time t=.*: the log has no clock",
        ),
        ((ODOM, META), r"log.jsonl:1: missing meta record"),
        (
            (META.replace('"version":1', '"version":2'), ODOM),
            r"log.jsonl:1: unsupported detection log version 2",
        ),
        ((META.replace('"version":1', '"version":"1"'), ODOM), r"unsupported detection log version \"1\""),
        ((META.replace(',"version":1', ""), ODOM), r"log.jsonl:1: meta record has no 'version'"),
        ((META.replace('"frame":"odom"', '"frame":"map"'), ODOM), r"'frame' must be \"odom\""),
        ((META.replace('"fx":615', '"fx":0'), ODOM), r"fx and fy must be positive"),
        ((META.replace('"fx":615,', ""), ODOM), r"missing field camera\.'fx'"),
        ((META.replace('"roll":0,', ""), ODOM), r"missing field camera_pose\.'roll'"),
    ],
)
def test_malformed_lines_name_file_line_and_problem(tmp_path: Path, lines, expected: str) -> None:
    path = write(tmp_path, *lines)
    with pytest.raises(InputError, match=expected):
        read_log(path)


def test_empty_missing_and_unreadable_logs(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"empty log"):
        read_log(write(tmp_path, "", "   ", name="empty.jsonl"))
    (tmp_path / "zero.jsonl").write_text("")
    with pytest.raises(InputError, match=r"zero.jsonl: empty log"):
        read_log(tmp_path / "zero.jsonl")
    with pytest.raises(InputError, match=r"no such file"):
        read_log(tmp_path / "absent.jsonl")
    with pytest.raises(InputError, match=r"is a folder"):
        read_log(tmp_path)
    (tmp_path / "binary.jsonl").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(InputError, match=r"not a text file"):
        read_log(tmp_path / "binary.jsonl")
    with pytest.raises(InputError, match=r"missing meta record"):
        read_log(write(tmp_path, '{"type":"imu","t":0}', name="nometa.jsonl"))


def test_skip_bad_counts_and_warns(tmp_path: Path) -> None:
    path = write(tmp_path, META, ODOM, "{oops", '{"type":"odom","t":0.4}', DET, "[]")
    log = read_log(path, skip_bad=True)
    assert log.skipped_bad == 3
    assert [type(r).__name__ for r in log.records] == ["Odom", "Detections"]
    assert log.warnings[0].startswith("skipped 3 malformed line(s)") and "log.jsonl:3:" in log.warnings[0]
    # a bad meta record is never skipped: nothing after it could be read
    bad_meta = write(tmp_path, META.replace('"version":1', '"version":7'), ODOM, name="v7.jsonl")
    with pytest.raises(InputError, match=r"v7.jsonl:1: unsupported detection log version 7"):
        read_log(bad_meta, skip_bad=True)


def test_a_log_of_one_time_and_one_place_is_read(tmp_path: Path) -> None:
    """A session that ended at once writes a few records of one time and one pose: not refused."""
    assert len(read_log(write(tmp_path, META, ODOM, ODOM, ODOM)).records) == 3


def test_records_out_of_time_order_are_sorted_with_a_warning(tmp_path: Path) -> None:
    path = write(tmp_path, META, '{"type":"odom","t":1.0,"x":1,"y":0,"yaw":0}', ODOM)
    log = read_log(path)
    assert [r.t for r in log.records] == [0.0, 1.0]
    assert any("out of time order" in w for w in log.warnings)


def test_feature_source_round_trips_and_old_logs_read_as_camera(tmp_path: Path) -> None:
    records = [
        Meta(DEFAULT_CAMERA, DEFAULT_MOUNT),
        FeatureRecord(0.4, "door", 3.0, -1.0),
        FeatureRecord(0.5, "ConcaveCorner", 1.25, 2.5, source="lidar"),
    ]
    path = tmp_path / "sources.jsonl"
    write_log(path, records)
    lines = path.read_text().splitlines()
    assert '"source"' not in lines[1]  # a camera feature is written as before the field existed
    assert json.loads(lines[2])["source"] == "lidar"
    for line in lines:
        jsonschema.validate(json.loads(line), SCHEMA)
    log = read_log(path)
    assert log.records == records[1:]
    assert [f.source for f in log.features] == ["camera", "lidar"]
    old = write(tmp_path, META, '{"type":"feature","t":0.4,"class":"door","x":1,"y":2}', name="old.jsonl")
    assert read_log(old).features[0].source == "camera"
    bad = write(tmp_path, META, '{"type":"feature","t":0.4,"class":"door","x":1,"y":2,"source":"radar"}')
    with pytest.raises(InputError, match=r"log.jsonl:2: field 'source' must be one of camera, lidar"):
        read_log(bad)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(json.loads(bad.read_text().splitlines()[1]), SCHEMA)
