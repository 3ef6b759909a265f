"""``bim-init watch RECORDING --site SITE``: a kidnap is found lost within 15 m of travel and
recovered within 0.5 m and 5 degrees of the truth; a control raises no alarm; the JSON and the exit
codes are the issue's contract; a bag replays as its log does; bad input is one line, exit 2."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import pytest
import yaml
from typer.testing import CliRunner

from bimkit.schemas import schema_path
from initcli.cli.main import app
from initcli.io.log_records import Localiser, Odom, Scan
from initcli.io.log_writer import write_log
from initcli.ros.bag_writer import BagMessage, laser_scan, odometry, write_bag
from initcli.ros.nav2 import initial_pose_message
from initcli.ros.records import LASER_SCAN, ODOMETRY, POSE_WITH_COVARIANCE_STAMPED, InitialPose

RUNNER = CliRunner()


def _watch(*args: str | Path) -> tuple[int, str, str]:
    result = RUNNER.invoke(app, ["watch", *map(str, args)])
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def kidnap_run(corridor, tmp_path_factory):
    """``bim-init watch KIDNAP --site SITE --json --plot FILE``: (exit code, document, stderr, plot)."""
    plot = tmp_path_factory.mktemp("plot") / "watch.png"
    code, out, err = _watch(corridor.kidnap_log, "--site", corridor.site, "--json", "--plot", plot)
    return code, json.loads(out) if code in (0, 1) else None, err, plot


def test_a_kidnap_is_lost_then_recovered_at_the_truth(corridor, kidnap_run):
    code, doc, err, _ = kidnap_run
    assert code == 0, err
    kinds = [e["kind"] for e in doc["events"]]
    assert kinds[:2] == ["lost", "recovered"], doc["events"]
    lost, found = doc["events"][0], doc["events"][1]
    assert lost["t"] >= corridor.kidnap.splice_t  # never before the kidnap
    splice_travel = 9.0 * 1.01  # the first leg's odometry
    assert lost["travel"] - splice_travel <= 15.0
    truth = corridor.kidnap.truth_at(found["t"])
    pose = found["pose"]
    assert set(pose) == {"x", "y", "yaw"}
    assert math.hypot(pose["x"] - truth.x, pose["y"] - truth.y) <= 0.5
    assert abs(math.degrees(math.remainder(pose["yaw"] - truth.yaw, math.tau))) <= 5.0
    assert "pose" not in lost and lost["reason"]
    assert doc["exit_code"] == 0 and doc["state"] == "tracking"
    jsonschema.validate(doc, json.loads(schema_path("watch_result.schema.json").read_text()))
    assert "lost" not in kinds[2:], "the recovered pose is watched as right"


def test_a_right_localiser_is_never_lost(corridor):
    code, out, err = _watch(corridor.control_log, "--site", corridor.site, "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert [e for e in doc["events"] if e["kind"] == "lost"] == []
    assert doc["checks"] and max(c["statistic"] for c in doc["checks"]) < 0.8 / 2


def test_lost_and_not_recovered_exits_1(corridor, tmp_path):
    """A registration that is never unique (every other place counts as alike): lost, never found."""
    config = tmp_path / "site.yaml"
    config.write_text(
        yaml.safe_dump(
            {"site": {"path": str(corridor.site)}, "registration": {"margin": 1.0, "see_through": 0}}
        )
    )
    code, out, err = _watch(corridor.kidnap_log, "--config", config)
    assert code == 1, (out, err)
    assert "lost 1 time(s), recovered 0" in out


def test_the_plot_is_written(kidnap_run):
    code, _, err, plot = kidnap_run
    assert code == 0, err
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _bag_messages(records) -> list[BagMessage]:
    out = []
    for r in records:
        if isinstance(r, Odom):
            out.append(BagMessage("/odom", ODOMETRY, r.t, odometry(r.t, r.pose)))
        elif isinstance(r, Scan):
            out.append(BagMessage("/scan", LASER_SCAN, r.t, laser_scan(r.t, r)))
        elif isinstance(r, Localiser):
            pose = InitialPose(r.t, r.x, r.y, r.yaw, (0.0,) * 36)
            out.append(
                BagMessage("/amcl_pose", POSE_WITH_COVARIANCE_STAMPED, r.t, initial_pose_message(pose))
            )
    return out


def test_a_bag_replays_as_its_log(corridor, kidnap_run, tmp_path):
    bag = write_bag(tmp_path / "b.mcap", _bag_messages(corridor.kidnap.records))
    code, out, err = _watch(bag, "--site", corridor.site, "--json")
    assert code == 0, err
    from_bag = [(e["kind"], round(e["travel"], 1)) for e in json.loads(out)["events"]]
    assert from_bag == [(e["kind"], round(e["travel"], 1)) for e in kidnap_run[1]["events"]]


def test_bad_input_is_one_line(corridor, tmp_path):
    no_pose = tmp_path / "no_pose.jsonl"
    write_log(no_pose, [r for r in corridor.control.records if not isinstance(r, Localiser)])
    for args, words in (
        ((no_pose, "--site", corridor.site), "no localiser pose"),
        ((corridor.control_log,), "--site SITE"),
        ((corridor.control_log, "--site", tmp_path / "nowhere"), "no such file"),
        ((), "give a recording"),
    ):
        code, out, err = _watch(*args)
        assert code == 2, (args, out, err)
        assert words in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
