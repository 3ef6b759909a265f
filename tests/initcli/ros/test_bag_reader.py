"""bag2log's reader: bags of every format and perception kind -> detection-log records."""

from __future__ import annotations

import math
import sqlite3

import numpy as np
import pytest

from benchmarks._recordings import CAMERA, MOUNT, POINTS, door_image, make_recording, write
from bimkit.errors import InputError
from initcli.core.geometry.projection import detections_to_odom
from initcli.detector.runtime import Detector
from initcli.io.detection_log import Detections, Meta, Odom, Scan
from initcli.ros.bag_reader import BagSource, bag_to_records, parse_class_names
from initcli.ros.bag_writer import BagMessage, depth_image
from initcli.ros.records import IMAGE, Bag2LogOptions


def _split(records):
    meta = records[0]
    assert isinstance(meta, Meta)
    return (
        meta,
        [r for r in records if isinstance(r, Detections)],
        [r for r in records if isinstance(r, Odom)],
    )


def _check_geometry(records, rec):
    """Every box centre and depth goes back (Eq. 1-2) to the feature point it was made from."""
    meta, dets, odom = _split(records)
    assert meta.camera == CAMERA
    for got, want in zip(
        (
            meta.camera_pose.x,
            meta.camera_pose.y,
            meta.camera_pose.z,
            meta.camera_pose.pitch,
            meta.camera_pose.yaw,
        ),
        (MOUNT.x, MOUNT.y, MOUNT.z, MOUNT.pitch, MOUNT.yaw),
        strict=True,
    ):
        assert got == pytest.approx(want, abs=1e-9)
    assert odom[0].x == pytest.approx(0.0, abs=1e-9) and odom[0].yaw == pytest.approx(0.0, abs=1e-9)
    assert len(dets) == len(rec.image_times)
    seen = 0
    for d in dets:
        truth = rec.truth_local[min(rec.truth_local, key=lambda t: abs(t - d.t))]
        assert d.pose.distance_to(truth) < 2e-3  # interpolated between 20 Hz odometry
        for o in d.objects:
            p = detections_to_odom(
                np.array([o.bbox]), np.array([o.depth]), meta.camera, meta.camera_pose, d.pose
            )[0]
            assert np.allclose(p, POINTS[o.cls], atol=0.02), (o, p)
            seen += 1
    assert seen >= len(dets)


NAMES = parse_class_names("door,lift,stairs")


@pytest.mark.parametrize(
    ("fmt", "layout"),
    [
        *((fmt, layout) for fmt in ("sqlite3", "mcap") for layout in ("humble", "galactic", "foxy")),
        ("ros1", "noetic"),
    ],
)
def test_detections_in_every_format_and_layout(tmp_path, fmt, layout):
    """Bags written with rosbags from each release's vision_msgs definitions (Noetic's ids are int64)."""
    rec = make_recording(layout=layout)
    bag = write(tmp_path, rec, fmt, layout)
    records, stats = bag_to_records(bag, Bag2LogOptions(class_names=NAMES if layout == "noetic" else None))
    _check_geometry(records, rec)
    assert stats.images == len(rec.image_times) and stats.without_depth == 0
    assert any(isinstance(r, Scan) for r in records)
    times = [r.t for r in records[1:]]
    assert times == sorted(times)


def test_odometry_from_tf_and_millimetre_depth(tmp_path):
    rec = make_recording(odom_source="tf", depth_encoding="16UC1")
    records, _ = bag_to_records(write(tmp_path, rec, "mcap"))
    _check_geometry(records, rec)


def test_numeric_class_ids_are_named(tmp_path):
    rec = make_recording(numeric=True)
    bag = write(tmp_path, rec, "mcap")
    records, stats = bag_to_records(bag)
    assert {o.cls for d in _split(records)[1] for o in d.objects} <= {"0", "1", "2"}
    assert any("--class-names" in w for w in stats.warnings)
    records, _ = bag_to_records(bag, Bag2LogOptions(class_names=parse_class_names("door,lift,stairs")))
    _check_geometry(records, rec)
    records, _ = bag_to_records(bag, Bag2LogOptions(class_names=parse_class_names("0=door,1=lift,2=stairs")))
    _check_geometry(records, rec)


def _drop_definitions(bag, like: str = "%") -> int:
    """Delete the message definitions of a ROS 2 sqlite3 bag, as a Foxy or Humble db3 has none."""
    db = next(bag.glob("*.db3"))
    with sqlite3.connect(db) as con:
        return con.execute("DELETE FROM message_definitions WHERE topic_type LIKE ?", (like,)).rowcount


@pytest.mark.parametrize("layout", ["humble", "galactic", "foxy"])
@pytest.mark.parametrize("like", ["vision_msgs/%", "%"])
def test_sqlite_bag_without_definitions_is_read_in_its_layout(tmp_path, layout, like):
    """A Foxy db3 carries no definitions: its bytes are not Humble's (Detection2D ends with
    source_img, is_tracking, tracking_id), and it is read in the layout its messages parse in."""
    rec = make_recording(layout=layout)
    bag = write(tmp_path, rec, "sqlite3", layout)
    assert _drop_definitions(bag, like) >= 1
    records, _ = bag_to_records(bag)
    _check_geometry(records, rec)
    with BagSource(bag) as source:
        assert source.vision_layout == ("foxy" if layout == "foxy" else "humble")


def test_vision_bytes_of_no_known_layout_name_the_bag_and_topic(tmp_path):
    """Messages that parse in no layout (here: a count of 5 detections and nothing after it)."""
    bag = write(tmp_path, make_recording(duration=1.0), "sqlite3")
    _drop_definitions(bag)
    db = next(bag.glob("*.db3"))
    with sqlite3.connect(db) as con:
        (topic_id,) = con.execute("SELECT id FROM topics WHERE name = '/detections'").fetchone()
        con.execute("UPDATE messages SET data = X'000100000500' WHERE topic_id = ?", (topic_id,))
    with pytest.raises(InputError, match=r"rec: /detections: the vision_msgs/msg/Detection2DArray messages"):
        bag_to_records(bag)


@pytest.mark.parametrize("perception", ["image", "compressed"])
def test_images_run_the_onnx_detector(tmp_path, perception):
    rec = make_recording(perception=perception, duration=1.0)
    records, stats = bag_to_records(write(tmp_path, rec, "mcap"))
    _, dets, _ = _split(records)
    assert stats.images == len(dets) == len(rec.image_times)
    detector = Detector("default", conf=Bag2LogOptions().score_threshold)
    for i, d in enumerate(dets):
        want = detector.detect(door_image(i))
        assert [o.cls for o in d.objects] == [w.class_name for w in want]
        for o, w in zip(d.objects, want, strict=True):
            assert o.bbox == pytest.approx(w.box, abs=0.01)


def test_rate_limits_the_images(tmp_path):
    rec = make_recording()
    records, stats = bag_to_records(write(tmp_path, rec, "mcap"), Bag2LogOptions(rate=2.0))
    kept = len(_split(records)[1])
    assert kept == math.ceil(len(rec.image_times) / 3)  # 5 Hz images, at most 2 Hz: every third
    assert stats.skipped_rate == len(rec.image_times) - kept
    gaps = np.diff([d.t for d in _split(records)[1]])
    assert (gaps >= 0.5 - 1e-6).all()


def test_real_camera_optical_frame_convention(tmp_path):
    """A RealSense-style /tf_static: camera_link level at (0.2, 0, 1), optical frame rotated
    by the REP 103 quaternion (-0.5, 0.5, -0.5, 0.5): the mount is level and straight ahead."""
    rec = make_recording(duration=1.0)
    for m in rec.messages:
        if m.topic == "/tf_static":
            body, optical = m.value["transforms"]
            body["transform"]["translation"] = {"x": 0.2, "y": 0.0, "z": 1.0}
            body["transform"]["rotation"] = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
            optical["transform"]["rotation"] = {"x": -0.5, "y": 0.5, "z": -0.5, "w": 0.5}
    meta = bag_to_records(write(tmp_path, rec, "mcap"))[0][0]
    m = meta.camera_pose
    assert (m.x, m.y, m.z) == pytest.approx((0.2, 0.0, 1.0))
    assert (m.roll, m.pitch, m.yaw) == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


# --- bad input: one InputError each -----------------------------------------------------------------


def _without(rec, topic):
    rec.messages = [m for m in rec.messages if m.topic != topic]
    return rec


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        (lambda r: _without(r, "/camera/depth/image"), "no aligned depth image"),
        (lambda r: _without(r, "/camera/color/camera_info"), "no sensor_msgs/CameraInfo"),
        (lambda r: _without(r, "/tf_static"), "no transform base_link -> cam_optical"),
        (lambda r: _without(_without(r, "/odom"), "/tf"), "no odometry"),
    ],
)
def test_missing_inputs(tmp_path, edit, fragment):
    bag = write(tmp_path, edit(make_recording(duration=1.0)), "mcap")
    with pytest.raises(InputError, match=fragment):
        bag_to_records(bag)


def test_two_depth_images_list_the_candidates(tmp_path):
    rec = make_recording(duration=1.0)
    t = rec.image_times[0]
    rec.messages.append(BagMessage("/other/depth", IMAGE, t, depth_image(t, np.zeros((4, 4), np.float32))))
    with pytest.raises(InputError, match=r"several depth images.*/camera/depth/image.*/other/depth"):
        bag_to_records(write(tmp_path, rec, "mcap"))
    records, _ = bag_to_records(tmp_path / "rec.mcap", Bag2LogOptions(depth_topic="/camera/depth/image"))
    assert len(_split(records)[1]) == len(rec.image_times)


def test_named_topic_must_exist(tmp_path):
    bag = write(tmp_path, make_recording(duration=1.0), "mcap")
    with pytest.raises(InputError, match=r"no topic /nope \(--odom-topic\).*/odom \(nav_msgs/msg/Odometry"):
        bag_to_records(bag, Bag2LogOptions(odom_topic="/nope"))


def test_depth_out_of_sync(tmp_path):
    rec = make_recording(duration=1.0)
    for m in rec.messages:
        if m.topic == "/camera/depth/image":
            m.value["header"]["stamp"]["sec"] -= 1
    with pytest.raises(InputError, match="none with an aligned depth image"):
        bag_to_records(write(tmp_path, rec, "mcap"))


def test_clock_jumping_back(tmp_path):
    rec = make_recording(duration=3.0)
    odoms = [m for m in rec.messages if m.topic == "/odom"]
    odoms[30].value["header"]["stamp"]["sec"] -= 5
    with pytest.raises(InputError, match=r"/odom: the clock jumps back by 4\.950 s at message 31"):
        bag_to_records(write(tmp_path, rec, "mcap"))


@pytest.mark.parametrize("content", [b"", b"not a bag at all" * 10])
def test_unreadable_bag(tmp_path, content):
    bad = tmp_path / "bad.bag"
    bad.write_bytes(content)
    with pytest.raises(InputError, match="not a readable ROS bag"):
        bag_to_records(bad)
    with pytest.raises(InputError, match="no such bag"):
        bag_to_records(tmp_path / "missing.mcap")


def test_colour_image_is_not_mistaken_for_depth(tmp_path):
    """Two sensor_msgs/Image topics, told apart by encoding (bgr8 colour, 32FC1 depth)."""
    rec = make_recording(perception="image", duration=0.5)
    records, _ = bag_to_records(write(tmp_path, rec, "ros1"))
    assert len(_split(records)[1]) == len(rec.image_times)
    assert door_image(0).shape == (CAMERA.height, CAMERA.width, 3)
