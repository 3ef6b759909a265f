"""``bim-init watch --config site.yaml`` beside a live robot over loopback rosbridge: a recording of
the corridor world replayed as a robot publishes it (odometry and scans on the robot's clock, a
localiser on ``/amcl_pose`` that keeps tracking the old place after a kidnap and takes a pose sent
on ``/initialpose``). The watch publishes its state and diagnostics, finds the robot lost, sends the
recovered pose stamped on the robot's clock within 0.5 m and 5 degrees of the truth, AMCL's echo
confirms it, and it exits 0."""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import pytest
import yaml
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.core.geometry.se2 import Pose2D
from initcli.io.log_records import Localiser, Odom, Scan
from initcli.ros.nav2 import initial_pose_message, pose_dict, stamp_dict
from initcli.ros.records import InitialPose
from initcli.ros.rosbridge_driver import header_stamp
from initcli.ros.tf import quaternion_yaw
from tests.initcli.ros.rosbridge_server import RosbridgeServer
from tests.initcli.watch.kidnap_world import Recording

pytest.importorskip("roslibpy")

T0 = 1_700_000_000.0
SPEED = 4.0  # the recording replayed this much faster than it was driven


class ReplayRobot:
    """Publishes a recording's odometry, scans and localiser poses in time order (``SPEED`` x), then
    stands (the last ones again every 0.1 s); a pose on ``/initialpose`` is taken by its localiser,
    carried on by odometry from then on."""

    def __init__(self, server: RosbridgeServer, recording: Recording) -> None:
        self.server, self.recording = server, recording
        self.odom: list[tuple[float, Pose2D]] = []
        self.taken: Pose2D | None = None  # the localiser's odom -> map once it took a pose
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        server.hooks[("publish", "/initialpose")] = self._on_initialpose

    def __enter__(self) -> ReplayRobot:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5)

    def _on_initialpose(self, op: dict[str, Any]) -> None:
        msg = op["msg"]
        stamp = header_stamp(msg)
        p, q = msg["pose"]["pose"]["position"], msg["pose"]["pose"]["orientation"]
        sent = Pose2D(p["x"], p["y"], quaternion_yaw(q["x"], q["y"], q["z"], q["w"]))
        odom = min(self.odom, key=lambda s: abs(s[0] - stamp))[1]
        self.taken = sent * odom.inverse()

    def _send(self, record: Odom | Scan | Localiser) -> None:
        stamp = T0 + record.t
        head = {"stamp": stamp_dict(stamp), "frame_id": "odom"}
        if isinstance(record, Odom):
            self.odom.append((stamp, record.pose))
            msg = {
                "header": head,
                "child_frame_id": "base_link",
                "pose": {"pose": pose_dict(record.x, record.y, record.yaw)},
            }
            self.server.send("/odom", msg)
        elif isinstance(record, Scan):
            self.server.send(
                "/scan",
                {
                    "header": {**head, "frame_id": "base_link"},
                    "angle_min": record.angle_min,
                    "angle_max": record.angle_min + record.angle_increment * (len(record.ranges) - 1),
                    "angle_increment": record.angle_increment,
                    "range_min": 0.05,
                    "range_max": record.range_max,
                    "ranges": list(record.ranges),
                },
            )
        else:
            pose = record.pose if self.taken is None else self.taken * self.odom[-1][1]
            message = initial_pose_message(InitialPose(stamp, pose.x, pose.y, pose.yaw, (0.0,) * 36))
            self.server.send("/amcl_pose", message)

    def _run(self) -> None:
        deadline = time.monotonic() + 10
        while not self.server.subscriptions.get("/amcl_pose") and time.monotonic() < deadline:
            time.sleep(0.01)
        started = time.monotonic()
        body = [r for r in self.recording.records if isinstance(r, Odom | Scan | Localiser)]
        last: dict[type, Any] = {}
        for record in body:
            wait = started + record.t / SPEED - time.monotonic()
            if wait > 0 and self._stop.wait(wait):
                return
            self._send(record)
            last[type(record)] = record
        t = body[-1].t
        while not self._stop.wait(0.1 / SPEED):  # standing: the clock runs on
            t += 0.1
            for record in last.values():
                self._send(
                    type(record)(t, *[getattr(record, f) for f in list(record.__dataclass_fields__)[1:]])
                )


def test_the_live_watch_finds_the_robot_again_and_tells_nav2(corridor, tmp_path):
    with RosbridgeServer(amcl=True) as server, ReplayRobot(server, corridor.kidnap) as robot:
        config = tmp_path / "live.yaml"
        config.write_text(
            yaml.safe_dump(
                {
                    "site": {"path": str(corridor.site)},
                    "robot": {
                        "driver": "rosbridge",
                        "rosbridge": {"host": "127.0.0.1", "port": server.port, "camera_wait": 0.5},
                    },
                    "nav2": {"advertise_delay": 0.1, "confirm": {"timeout": 3.0, "republish_period": 0.5}},
                }
            )
        )
        duration = corridor.kidnap.truth[-1][0] / SPEED + 2.0
        result = CliRunner().invoke(app, ["watch", "--config", str(config), "--duration", f"{duration:.1f}"])
        assert result.exit_code == 0, (result.stdout, result.stderr)
        assert "lost" in result.stdout and "recovered" in result.stdout
        sent = server.published("/initialpose")
        assert sent, "no pose sent to Nav2"
        stamp = header_stamp(sent[0])
        p = sent[0]["pose"]["pose"]["position"]
        q = sent[0]["pose"]["pose"]["orientation"]
        truth = corridor.kidnap.truth_at(stamp - T0)
        assert math.hypot(p["x"] - truth.x, p["y"] - truth.y) <= 0.5
        yaw = quaternion_yaw(q["x"], q["y"], q["z"], q["w"])
        assert abs(math.degrees(math.remainder(yaw - truth.yaw, math.tau))) <= 5.0
        assert stamp >= T0 + corridor.kidnap.splice_t, "stamped on the robot's clock, after the kidnap"
        assert robot.taken is not None
    states = [m["data"] for m in server.published("/bim_init/state")]
    assert {"tracking", "lost"} <= set(states) and states[-1] == "tracking"
    levels = [s["level"] for m in server.published("/diagnostics") for s in m["status"]]
    assert 0 in levels and 2 in levels
    assert all(header_stamp(m) >= T0 for m in server.published("/diagnostics"))


def _live_config(tmp_path, corridor, port: int, **sections: dict) -> str:
    doc = {
        "site": {"path": str(corridor.site)},
        "robot": {
            "driver": "rosbridge",
            "rosbridge": {"host": "127.0.0.1", "port": port, "camera_wait": 0.5},
        },
        "nav2": {"advertise_delay": 0.1, "confirm": {"timeout": 3.0, "republish_period": 0.5}},
        **sections,
    }
    path = tmp_path / "live.yaml"
    path.write_text(yaml.safe_dump(doc))
    return str(path)


def test_lost_with_watch_drive_the_robot_explores_then_is_handed_back(corridor, tmp_path):
    """``watch.drive: true`` and a place never found again: nothing on /cmd_vel while the pose is
    right, wall following once lost, a zero Twist last."""
    with RosbridgeServer() as server, ReplayRobot(server, corridor.kidnap):
        config = _live_config(
            tmp_path,
            corridor,
            server.port,
            watch={"drive": True},
            registration={"margin": 1.0, "see_through": 0},
        )
        duration = corridor.kidnap.truth[-1][0] / SPEED + 1.0
        result = CliRunner().invoke(app, ["watch", "--config", config, "--duration", f"{duration:.1f}"])
        assert result.exit_code == 1, (result.stdout, result.stderr)  # lost, not recovered
        ops = list(server.ops)
    lost_at = next(
        i
        for i, o in enumerate(ops)
        if o.get("op") == "publish" and o.get("topic") == "/bim_init/state" and o["msg"]["data"] == "lost"
    )
    commands = [
        (i, o["msg"]) for i, o in enumerate(ops) if o.get("op") == "publish" and o.get("topic") == "/cmd_vel"
    ]
    assert commands, "no exploring while lost"
    assert all(i > lost_at for i, _ in commands), "/cmd_vel before the pose was lost"
    assert any(m["linear"]["x"] != 0.0 or m["angular"]["z"] != 0.0 for _, m in commands)
    last = commands[-1][1]
    assert last["linear"]["x"] == 0.0 and last["angular"]["z"] == 0.0


def test_the_localiser_from_tf_is_map_to_odom_times_the_robots_odometry():
    """``--pose-topic tf`` live: each ``map -> odom`` on /tf composed with the odometry the robot sent
    at its stamp (Nav2's ``map -> base_link``); other parents ignored."""
    from initcli.watch.live import LocaliserFeed

    class Link:
        subscribed: list[str] = []

        def subscribe(self, topic, msgtype, callback):  # type: ignore[no-untyped-def]
            self.subscribed.append(topic)

    class Driver:
        def raw_odometry_at(self, stamp):  # type: ignore[no-untyped-def]
            return Pose2D(1.0, 0.0, math.pi / 2) if abs(stamp - T0) < 0.2 else None

    class Watcher:
        got: list[tuple[float, Pose2D]] = []

        def localiser(self, t, pose):  # type: ignore[no-untyped-def]
            self.got.append((t, pose))

    link, watcher = Link(), Watcher()
    feed = LocaliserFeed(link, Driver(), "tf")  # type: ignore[arg-type]
    assert link.subscribed == ["/tf"]
    q = {"x": 0.0, "y": 0.0, "z": math.sin(math.pi / 4), "w": math.cos(math.pi / 4)}  # 90 degrees
    feed._on_tf(
        {
            "transforms": [
                {
                    "header": {"stamp": stamp_dict(T0), "frame_id": "map"},
                    "child_frame_id": "odom",
                    "transform": {"translation": {"x": 5.0, "y": 2.0, "z": 0.0}, "rotation": q},
                },
                {
                    "header": {"stamp": stamp_dict(T0), "frame_id": "odom"},
                    "child_frame_id": "base_link",
                    "transform": {"translation": {"x": 9.0, "y": 9.0, "z": 0.0}, "rotation": q},
                },
            ]
        }
    )
    feed.drain(watcher)  # type: ignore[arg-type]
    ((t, pose),) = watcher.got
    assert t == T0 and math.isclose(pose.x, 5.0, abs_tol=1e-9) and math.isclose(pose.y, 3.0, abs_tol=1e-9)
    assert math.isclose(pose.yaw, math.pi, abs_tol=1e-9) or math.isclose(pose.yaw, -math.pi, abs_tol=1e-9)
