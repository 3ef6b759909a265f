"""``bim-init run`` on a live robot served over loopback rosbridge: the simulated robot of
``block_a`` (tests/initcli/ros/sim_robot.py), its odometry on the robot's clock (1.7e9 s), which
drives on by itself once the session has claimed. The pose reaches ``/initialpose`` every time,
stamped within 0.5 s of the robot's clock and within 0.15 m / 3 degrees of its true pose at that
stamp, is confirmed by the AMCL stand-in, and ``summary.json`` holds both poses; ROS 1 and ROS 2
stamps. A run whose odometry stops keeps its log."""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.config import load_config
from initcli.config.building import prepare_site
from initcli.core.geometry.se2 import Pose2D
from initcli.ros.rosbridge_driver import header_stamp
from initcli.ros.tf import quaternion_yaw
from tests.helpers import SAMPLES
from tests.initcli.ros.rosbridge_server import RosbridgeServer
from tests.initcli.ros.sim_robot import SimRobot

pytest.importorskip("roslibpy")

START = Pose2D(10.0, 11.0, 0.0)  # block_a: initialises in ~45 s of robot time (seed 3)


def _config(tmp_path: Path, port: int, camera: dict | None = None, changes: dict | None = None) -> Path:
    """block_a's config for a live robot on ``port``; ``camera``: changes to its camera: section;
    ``changes``: to other sections (section -> its keys)."""
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    doc["camera"].update(camera or {})
    doc["site"]["path"] = str(SAMPLES / "block_a.ifc")
    doc["robot"]["driver"] = "rosbridge"
    doc["robot"]["rosbridge"] = {
        "host": "127.0.0.1",
        "port": port,
        "detections_topic": "/detections",
        "depth_topic": "/camera/depth/image",
    }
    doc["nav2"] = {"advertise_delay": 0.1, "confirm": {"timeout": 5.0, "republish_period": 0.5}}
    for key, values in (changes or {}).items():
        doc.setdefault(key, {}).update(values)
    path = tmp_path / "live.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("site")
    config = load_config(_config(tmp, 9090))
    return config, prepare_site(config, tmp)


@pytest.fixture
def fast_driver(monkeypatch):
    """The session's control period down to 30 ms: the robot steps in lockstep with the commands."""
    import initcli.session.live as live

    monkeypatch.setattr(live, "RosbridgeDriver", functools.partial(live.RosbridgeDriver, period=0.03))


def _pose(msg: dict) -> Pose2D:
    p, q = msg["pose"]["pose"]["position"], msg["pose"]["pose"]["orientation"]
    return Pose2D(p["x"], p["y"], quaternion_yaw(q["x"], q["y"], q["z"], q["w"]))


def _last_twist(server: RosbridgeServer) -> tuple[float, float] | None:
    twists = server.published("/cmd_vel")
    return (twists[-1]["linear"]["x"], twists[-1]["angular"]["z"]) if twists else None


def live_run(
    tmp_path: Path,
    site,
    ros1: bool = False,
    amcl_ignores: int = 1,
    camera: dict | None = None,
    seed: int = 3,
    start: Pose2D = START,
    changes: dict | None = None,
    **robot,
) -> dict:
    """One live run (the AMCL stand-in ignores the first ``amcl_ignores`` poses: re-sent, carried
    further); what was measured, for the last pose sent."""
    config, loaded = site
    with RosbridgeServer(rosapi=True, amcl=True, amcl_ignores=amcl_ignores, set_initial_pose=True) as server:
        path = _config(tmp_path, server.port, camera, changes)
        bot_config = load_config(path) if changes else config
        with SimRobot(server, bot_config, loaded, seed, start, ros1=ros1, **robot) as bot:
            out = tmp_path / "out"
            result = CliRunner().invoke(app, ["run", "--config", str(path), "--out", str(out), "--quiet"])
            received = list(bot.received)
            truths = list(bot.truths)
            server.wait_for(lambda: _last_twist(server) == (0.0, 0.0), 2)
            last_twist = _last_twist(server)
            subscribed = {o["topic"] for o in server.of("subscribe")}
    summary = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else None
    measured: dict = {
        "exit_code": result.exit_code,
        "output": result.output,
        "summary": summary,
        "sent": received,
    }
    measured["last_twist"] = last_twist
    measured["subscribed"] = subscribed
    measured["bot"] = bot
    measured["stderr"] = result.stderr
    if received:
        robot_clock, msg = received[-1]
        stamp = header_stamp(msg)
        truth = min(truths, key=lambda s: abs(s[0] - stamp))[1]
        ours = _pose(msg)
        measured |= {
            "stamp": stamp,
            "stamp_offset_s": robot_clock - stamp,  # the robot's clock when it arrived, minus its stamp
            "error_m": ours.distance_to(truth),
            "error_deg": math.degrees(ours.yaw_error(truth)),
            "stamp_fields": set(msg["header"]["stamp"]),
        }
    return measured


@pytest.mark.parametrize("ros1", [False, True], ids=["ros2", "ros1"])
def test_a_live_run_delivers_the_carried_pose_on_the_robots_clock(tmp_path, site, fast_driver, ros1) -> None:
    m = live_run(tmp_path, site, ros1=ros1)
    assert m["exit_code"] == 0, m["output"]
    s = m["summary"]
    assert s["success"] is True and m["sent"]
    assert m["stamp_fields"] == ({"secs", "nsecs"} if ros1 else {"sec", "nanosec"})
    assert m["stamp"] > 1.7e9 and 0.0 <= m["stamp_offset_s"] < 0.5  # on the robot's clock, not behind it
    assert m["error_m"] < 0.15 and m["error_deg"] < 3.0
    claim, published = s["claim"], s["published"]
    assert published["stamp"] > claim["stamp"]  # the robot drove on: carried forward
    assert published["stamp"] == pytest.approx(m["stamp"], abs=1e-6)  # the summary's is the last one sent
    assert published["x"] == pytest.approx(m["sent"][-1][1]["pose"]["pose"]["position"]["x"], abs=1e-4)
    moved = math.hypot(published["x"] - claim["x"], published["y"] - claim["y"])
    assert moved > 0.05
    assert published["covariance"][0][0] > s["covariance"][0][0]  # grown by the odometry noise
    d = s["delivery"]
    assert d["confirmed"] is True and d["flushed"] is True and d["advertised"] == "rosapi"
    assert d["sends"] == len(m["sent"]) == 2  # the first was ignored: re-sent, carried further
    assert d["set_initial_pose"]["called"] is True
    assert m["last_twist"] == (0.0, 0.0)


def test_a_live_run_whose_odometry_stops_keeps_its_log(tmp_path, site, fast_driver) -> None:
    m = live_run(tmp_path, site, stop_after=60)
    assert m["exit_code"] == 2 and "no odometry" in m["output"] and "Traceback" not in m["output"]
    s = m["summary"]
    assert s["success"] is False and "no odometry" in s["reason"] and not m["sent"]
    assert m["last_twist"] == (0.0, 0.0)  # the robot's last command
    log = [json.loads(line) for line in (tmp_path / "out" / "session.jsonl").read_text().splitlines()]
    assert sum(r.get("type") == "odom" for r in log) >= 55  # every step it drove is kept


def test_a_live_run_takes_the_camera_from_camera_info_and_tf_static(tmp_path, site, fast_driver) -> None:
    wrong = {"fx": 380.0, "pose": {"x": 0.2, "y": 0.0, "z": 1.3, "roll": 0.0, "pitch": 0.0, "yaw": 0.1}}
    m = live_run(tmp_path, site, camera=wrong, amcl_ignores=0)
    assert m["exit_code"] == 0, m["output"]
    s = m["summary"]
    assert s["camera"]["intrinsics"] == "CameraInfo /camera/color/camera_info"
    assert s["camera"]["mount"] == "/tf_static base_link -> camera_color_optical_frame"
    warnings = [line for line in m["stderr"].splitlines() if "warning" in line]
    assert len(warnings) == 2 and "fx 320" in warnings[0] and "fx 380" in warnings[0]
    assert "z 1.000" in warnings[1] and "z 1.300" in warnings[1]
    assert m["error_m"] < 0.15 and m["error_deg"] < 3.0  # matched with the robot's camera, not the YAML's


def test_an_interrupted_live_run_keeps_its_log_and_stops_the_robot(tmp_path, site, monkeypatch) -> None:
    import initcli.session.live as live

    class Interrupted(live.RosbridgeDriver):  # Ctrl-C at the 40th step
        def step(self, v: float, w: float):
            self.steps = getattr(self, "steps", 0) + 1
            if self.steps == 40:
                raise KeyboardInterrupt
            return super().step(v, w)

    monkeypatch.setattr(live, "RosbridgeDriver", functools.partial(Interrupted, period=0.03))
    m = live_run(tmp_path, site)
    assert m["exit_code"] != 0 and not m["sent"]
    s = m["summary"]
    assert s["success"] is False and s["reason"] == "stopped: interrupted (Ctrl-C or SIGTERM)"
    log = [json.loads(line) for line in (tmp_path / "out" / "session.jsonl").read_text().splitlines()]
    assert sum(r.get("type") == "odom" for r in log) >= 39
    assert m["last_twist"] == (0.0, 0.0)


LASER = Pose2D(0.15, -0.05, math.pi / 2)  # the laser turned 90 degrees, off the base's centre


def test_a_live_robot_without_a_camera_runs_on_its_lidar_from_its_mount(tmp_path, site, fast_driver) -> None:
    """No detections topic (rosapi lists none), 720 beams from a laser turned 90 degrees at an offset
    (/tf_static): the session runs to its end on the lidar, its scans carried into the base frame."""
    changes = {"lidar": {"beams": 720}, "limits": {"max_time": 12.0}}
    m = live_run(tmp_path, site, changes=changes, has_camera=False, laser=LASER)
    assert "Traceback" not in m["output"], m["output"]
    s = m["summary"]
    assert s is not None and s["camera_absent"] is True and s["camera"]["absent"] is True
    warnings = [line for line in m["stderr"].splitlines() if "warning" in line]
    assert len(warnings) == 1 and "no publisher of /detections" in warnings[0], m["stderr"]
    assert "/detections" not in m["subscribed"] and "/camera/depth/image" not in m["subscribed"]
    lidar = s["lidar"]
    assert lidar["mount_from"] == "/tf_static base_link -> laser" and lidar["frame"] == "laser"
    assert lidar["mount"] == {"x": 0.15, "y": -0.05, "yaw_deg": 90.0} and lidar["scans_dropped"] == 0
    log = [json.loads(line) for line in (tmp_path / "out" / "session.jsonl").read_text().splitlines()]
    meta = log[0]
    assert meta["camera_absent"] is True and "camera" not in meta
    assert meta["lidar_mount"]["yaw"] == pytest.approx(math.pi / 2)
    assert not [r for r in log if r.get("type") == "detections"]
    scans = [r for r in log if r.get("type") == "scan"]
    assert len(scans) >= 5 and sum(r.get("type") == "odom" for r in log) >= 50
    # The logged scans are in the base frame: each agrees with the walls cast from the base's true pose.
    bot, origin = m["bot"], s["clock"]["origin_stamp"]
    for scan in scans[1::4]:
        truth = bot.truth(origin + scan["t"])
        ranges = np.array([math.nan if r is None else r for r in scan["ranges"]])
        angles = scan["angle_min"] + scan["angle_increment"] * np.arange(len(ranges))
        cast = bot.sim.world.raycast(np.array([truth.x, truth.y]), angles + truth.yaw, 20.0, 0.0)
        ok = np.isfinite(ranges) & (cast < 19.0)
        assert ok.sum() > 300
        assert float(np.median(np.abs(ranges[ok] - cast[ok]))) < 0.05
