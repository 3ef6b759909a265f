"""``bim-init run`` with ``robot.driver: rosbridge``: the session drives a robot behind a loopback
rosbridge server fed from a recorded bag, publishes its state, and stops the robot when the robot's
odometry ends (one line on stderr, exit 2, nothing half-written)."""

from __future__ import annotations

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
        assert not out.exists()  # staged: nothing half-written
        states = [m["data"] for m in server.published("/bim_init/state")]
        assert states and states[0] in ("look", "explore")
        # Hypotheses go out as a PoseArray once the session matched (not before three features).
        for msg in server.published("/bim_init/hypotheses"):
            assert msg["header"]["frame_id"] == "map" and isinstance(msg["poses"], list)
        # The stop twist is the client's last message; the test server may still be reading it
        # when the command returns (seen on 2 busy cores), so wait for it to arrive.
        server.wait_for(lambda: _twists(server)[-1:] == [(0.0, 0.0)])
        twists = _twists(server)
        assert twists and twists[-1] == (0.0, 0.0)  # the robot was stopped
        assert any(v != 0.0 or w != 0.0 for v, w in twists)  # and it was driven before
