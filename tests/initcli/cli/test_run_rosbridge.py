"""``bim-init run`` with ``robot.driver: rosbridge``: the session drives a robot behind a loopback
rosbridge server fed from a recorded bag, publishes its state on the robot's clock, and stops the
robot when the robot's odometry ends (one line on stderr, exit 2), keeping what it saw: the session
log and a summary saying why it stopped."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from benchmarks._recordings import make_recording, write
from initcli.cli.main import app
from tests.helpers import SAMPLES
from tests.initcli.ros.rosbridge_server import RosbridgeServer
from tests.initcli.ros.test_rosbridge_driver import _replay, _twists

pytest.importorskip("roslibpy")


def test_a_live_session_drives_publishes_its_state_and_stops_the_robot(tmp_path: Path) -> None:
    bag = write(tmp_path, make_recording(duration=30.0), "mcap")
    stop = threading.Event()
    with RosbridgeServer() as server:
        config = tmp_path / "live.yaml"
        config.write_text(
            yaml.safe_dump(
                {
                    "site": {"path": str(SAMPLES / "block_a.ifc")},
                    "robot": {
                        "driver": "rosbridge",
                        "rosbridge": {
                            "host": "127.0.0.1",
                            "port": server.port,
                            "detections_topic": "/detections",
                            "depth_topic": "/camera/depth/image",
                            "camera_wait": 0.3,  # the replay sends no CameraInfo: the YAML's camera
                        },
                    },
                }
            )
        )
        feeder = threading.Thread(target=_replay, args=(server, bag, stop, 20.0), daemon=True)
        feeder.start()
        out = tmp_path / "out"
        result = CliRunner().invoke(app, ["run", "--config", str(config), "--out", str(out), "--quiet"])
        stop.set()
        feeder.join(timeout=5)
        assert result.exit_code == 2, result.output
        assert "no odometry" in result.output
        assert "Traceback" not in result.output
        assert f"what the run saw is in {out}" in result.output
        assert "warning: no CameraInfo on /camera/color/camera_info in 0.3 s" in result.stderr
        summary = json.loads((out / "summary.json").read_text())
        assert summary["success"] is False and summary["reason"].startswith("stopped: rosbridge: no odometry")
        origin = summary["clock"]["origin_stamp"]  # the bag's clock (1.7e9 s) when the session started
        assert 1.7e9 <= origin < 1.7e9 + 20.0
        assert summary["clock"]["stamps"].startswith("ros2")
        log = [json.loads(line) for line in (out / "session.jsonl").read_text().splitlines()]
        odom = [r for r in log if r.get("type") == "odom"]
        assert len(odom) > 5  # the odometry it saw is kept (one record per control step)
        # Session time is the robot's clock since the start: the bag's odometry ran 20 s.
        assert origin + odom[-1]["t"] == pytest.approx(1.7e9 + 20.0, abs=0.2)
        assert not [p for p in out.iterdir() if p.name.startswith(".bim-stage")]
        states = [m["data"] for m in server.published("/bim_init/state")]
        assert states and states[0] in ("look", "explore")
        # Hypotheses go out as a PoseArray once the session matched (not before three features).
        for msg in server.published("/bim_init/hypotheses"):  # stamped on the robot's clock
            assert msg["header"]["frame_id"] == "map" and isinstance(msg["poses"], list)
            assert abs(msg["header"]["stamp"]["sec"] - 1.7e9) < 60
        # The stop twist is the client's last message; the test server may still be reading it
        # when the command returns (seen on 2 busy cores), so wait for it to arrive.
        server.wait_for(lambda: _twists(server)[-1:] == [(0.0, 0.0)])
        twists = _twists(server)
        assert twists and twists[-1] == (0.0, 0.0)  # the robot was stopped
        assert any(v != 0.0 or w != 0.0 for v, w in twists)  # and it was driven before
