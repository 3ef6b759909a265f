"""bim-init bag2log and publish-pose on the command line: outputs, one-line errors, exit 2."""

from __future__ import annotations

import json
import math

import pytest
from typer.testing import CliRunner

from benchmarks._recordings import make_recording, write
from initcli.cli.main import app
from initcli.io.detection_log import read_log

runner = CliRunner()


def test_bag2log_writes_a_valid_log(tmp_path):
    bag = write(tmp_path, make_recording(numeric=True), "mcap")
    out = tmp_path / "log.jsonl"
    result = runner.invoke(app, ["bag2log", str(bag), "-o", str(out), "--class-names", "door,lift,stairs"])
    assert result.exit_code == 0, result.output
    log = read_log(out)
    assert len(log.detections) == 30 and log.odom
    assert {o.cls for d in log.detections for o in d.objects} <= {"door", "lift", "stairs"}
    assert "30 images" in result.stdout


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--image-topic", "/nope"], "no topic /nope (--image-topic)"),
        (["--image-topic", "/odom"], "/odom is nav_msgs/msg/Odometry, --image-topic needs"),
        (["--rate", "0"], "--rate: 0 must be > 0"),
        (["--class-names", "door,1=lift"], "--class-names"),
    ],
)
def test_bag2log_bad_input_is_one_line_exit_2(tmp_path, args, fragment):
    bag = write(tmp_path, make_recording(duration=1.0), "mcap")
    result = runner.invoke(app, ["bag2log", str(bag), "-o", str(tmp_path / "x.jsonl"), *args])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bim-init: error:") and fragment in lines[0]
    assert not (tmp_path / "x.jsonl").exists()


def test_bag2log_unreadable_bag(tmp_path):
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"\x89MCAP0\r\n garbage")
    result = runner.invoke(app, ["bag2log", str(bad), "-o", str(tmp_path / "x.jsonl")])
    assert result.exit_code == 2 and "not a readable ROS bag" in result.stderr


def _summary(tmp_path, success=True):
    doc = {
        "success": success,
        "reason": "initialised" if success else "no match",
        "pose": {"x": 5.0, "y": 2.0, "yaw": math.radians(90), "yaw_deg": 90.0} if success else None,
        "covariance": [[0.01, 0.002, 0.0], [0.002, 0.02, 0.0], [0.0, 0.0, 0.003]],
        "duration_s": 42.5,
    }
    path = tmp_path / "summary.json"
    path.write_text(json.dumps(doc))
    return path


def test_publish_pose_dry_run(tmp_path):
    result = runner.invoke(app, ["publish-pose", str(_summary(tmp_path)), "--dry-run"])
    assert result.exit_code == 0, result.output
    msg = json.loads(result.stdout)
    cov = msg["pose"]["covariance"]
    assert (cov[0], cov[1], cov[6], cov[7], cov[35]) == (0.01, 0.002, 0.002, 0.02, 0.003)
    assert sum(1 for c in cov if c) == 5
    assert msg["header"] == {"stamp": {"sec": 42, "nanosec": 500_000_000}, "frame_id": "map"}
    assert msg["pose"]["pose"]["position"] == {"x": 5.0, "y": 2.0, "z": 0.0}


def test_publish_pose_of_a_failed_session_is_exit_2(tmp_path):
    result = runner.invoke(app, ["publish-pose", str(_summary(tmp_path, success=False)), "--dry-run"])
    assert result.exit_code == 2 and "did not initialise (no match)" in result.stderr


def test_publish_pose_sends_once_over_rosbridge(tmp_path):
    pytest.importorskip("roslibpy")
    from tests.initcli.ros.rosbridge_server import RosbridgeServer

    with RosbridgeServer() as server:
        result = runner.invoke(
            app, ["publish-pose", str(_summary(tmp_path)), "--host", "127.0.0.1", "--port", str(server.port)]
        )
        assert result.exit_code == 0, result.output
        assert server.wait_for(lambda: server.published("/initialpose"), 5)
        assert len(server.published("/initialpose")) == 1
    result = runner.invoke(
        app, ["publish-pose", str(_summary(tmp_path)), "--host", "127.0.0.1", "--port", str(server.port)]
    )
    assert result.exit_code == 2 and "cannot reach rosbridge" in result.stderr
