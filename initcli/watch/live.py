"""``bim-init watch --config site.yaml``: beside Nav2 on a live robot over rosbridge.

The robot's odometry and scans (``robot.rosbridge``, the laser's mount from ``/tf_static``) and the
localiser's pose (``watch.pose_topic``, ``/amcl_pose`` by default; ``tf``: ``map -> odom`` on
``/tf`` composed with the odometry, Nav2's ``map -> base_link``) feed a
:class:`~initcli.watch.monitor.Watcher`, everything on the robot's clock (the odometry's stamps).
The watch's state goes to ``/bim_init/state`` (std_msgs/String: ``waiting``, ``tracking``,
``lost``) when it changes and once a second, with a ``diagnostic_msgs/DiagnosticArray`` on
``/diagnostics`` (OK tracking, WARN waiting, ERROR lost; the check's numbers as values). A
recovered pose goes to Nav2 as ``run`` sends one (:func:`initcli.ros.delivery.deliver_initial_pose`:
``/initialpose`` stamped on the robot's clock, carried forward by odometry, confirmed on AMCL's
pose topic). With ``watch.drive: true`` the robot explores while lost (:class:`Explorer`). The
watch runs until ``duration`` s pass (0: until Ctrl-C or SIGTERM)."""

from __future__ import annotations

import math
import queue
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from initcli.config import SessionConfig
from initcli.config.building import prepare_site
from initcli.core.filters.particle_filter import FilterNoise
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import SensorFrame
from initcli.io.log_records import NO_CAMERA, NO_MOUNT
from initcli.ros.delivery import CarriedPose, deliver_initial_pose
from initcli.ros.nav2 import stamp_dict, state_message
from initcli.ros.records import (
    DIAGNOSTIC_ARRAY,
    DIAGNOSTICS_TOPIC,
    POSE_FROM_TF,
    POSE_WITH_COVARIANCE_STAMPED,
    STATE_TOPIC,
    STRING,
    TF_MESSAGE,
)
from initcli.ros.rosbridge import RosbridgeLink
from initcli.ros.rosbridge_driver import RosbridgeDriver, header_stamp
from initcli.ros.tf import frame_name, quaternion_yaw
from initcli.watch.monitor import Watcher
from initcli.watch.records import EventKind, WatchEvent, WatchState
from initcli.watch.replay import WatchResult, watched_storey

__all__ = ["DIAGNOSTIC_NAME", "diagnostic_message", "watch_live"]

DIAGNOSTIC_NAME = "bim_init: watch"
MAP_FRAME = "map"  # REP 105
TF_TOPIC = "/tf"
STATUS_PERIOD_S = 1.0  # s between two state and diagnostics messages when nothing changes
RECOVERED_SD_M = 0.15  # m: the recovered pose's standard deviation sent to Nav2 (the checks' tolerance)
RECOVERED_SD_DEG = 3.0  # degrees: ... of its heading
_LEVELS = {WatchState.TRACKING: 0, WatchState.WAITING: 1, WatchState.LOST: 2}  # OK, WARN, ERROR


def diagnostic_message(
    stamp: float, watcher: Watcher, ros1: bool = False, state: WatchState | None = None
) -> dict[str, Any]:
    """The watch's ``diagnostic_msgs/DiagnosticArray``: one status (``state``, default the
    watcher's), the last check as values."""
    state = watcher.state if state is None else state
    last = watcher.checks[-1] if watcher.checks else None
    values = {"state": str(state), "storey": watcher.storey, "travel_m": f"{watcher.travel:.2f}"}
    if last is not None:
        values |= {
            "fit": f"{last.fit:.3f}",
            "through": f"{last.through:.3f}",
            "statistic": f"{last.statistic:.3f}",
            "threshold": f"{watcher.params.threshold:.3f}",
        }
    message = {
        WatchState.TRACKING: "the localiser's pose agrees with the model",
        WatchState.WAITING: "waiting for the localiser's pose, odometry and scans",
        WatchState.LOST: "the localiser's pose is wrong; re-initialising",
    }[state]
    status = {
        "level": _LEVELS[state],
        "name": DIAGNOSTIC_NAME,
        "message": message,
        "hardware_id": "",
        "values": [{"key": k, "value": v} for k, v in values.items()],
    }
    return {"header": {"stamp": stamp_dict(stamp, ros1), "frame_id": ""}, "status": [status]}


def _pose_message(msg: dict[str, Any]) -> tuple[float, Pose2D]:
    pose = msg["pose"]["pose"]
    p, q = pose["position"], pose["orientation"]
    yaw = quaternion_yaw(q.get("x", 0.0), q.get("y", 0.0), q.get("z", 0.0), q.get("w", 1.0))
    return header_stamp(msg), Pose2D(float(p["x"]), float(p["y"]), yaw)


class Explorer:
    """``watch.drive: true``: while the pose is lost, the robot explores as a session does (wall
    following on ``/cmd_vel``) to gather scans for the re-initialisation; otherwise it sends nothing
    (Nav2 drives), and a zero Twist once when it hands the robot back."""

    def __init__(self, cfg: SessionConfig, driver: RosbridgeDriver) -> None:
        from initcli.baselines.drive import WallFollowingExplorer

        self.cfg, self.driver = cfg, driver
        self.follow: WallFollowingExplorer | None = None
        driver.drive = False  # nothing on /cmd_vel until lost

    def step(self, frame: SensorFrame, state: WatchState) -> SensorFrame:
        from initcli.baselines.drive import WallFollowingExplorer

        if state is WatchState.LOST:
            if self.follow is None:
                self.follow = WallFollowingExplorer(self.cfg)
                self.driver.drive = True
            return self.driver.step(*self.follow.command(frame))
        self.hand_back()
        return self.driver.step(0.0, 0.0)

    def hand_back(self) -> None:
        if self.follow is not None:
            self.driver.stop()  # a zero Twist: the robot is Nav2's again
            self.driver.drive, self.follow = False, None


class LocaliserFeed:
    """The localiser's poses as they arrive (roslibpy's thread), handed to the watcher in the loop:
    a PoseWithCovarianceStamped topic, or ``map -> odom`` on /tf composed with the robot's odometry."""

    def __init__(self, link: RosbridgeLink, driver: RosbridgeDriver, topic: str) -> None:
        self.driver = driver
        self.poses: queue.Queue[tuple[float, Pose2D]] = queue.Queue()  # map poses
        self.corrections: queue.Queue[tuple[float, Pose2D]] = queue.Queue()  # map -> odom
        if topic == POSE_FROM_TF:
            link.subscribe(TF_TOPIC, TF_MESSAGE, self._on_tf)
        else:
            link.subscribe(topic, POSE_WITH_COVARIANCE_STAMPED, self._on_pose)

    def _on_pose(self, msg: dict[str, Any]) -> None:
        try:
            self.poses.put(_pose_message(msg))
        except (KeyError, TypeError, ValueError):
            return

    def _on_tf(self, msg: dict[str, Any]) -> None:
        for stamped in msg.get("transforms") or []:
            try:
                if frame_name(stamped["header"]["frame_id"]) != MAP_FRAME:
                    continue
                tr, q = stamped["transform"]["translation"], stamped["transform"]["rotation"]
                yaw = quaternion_yaw(q.get("x", 0.0), q.get("y", 0.0), q.get("z", 0.0), q.get("w", 1.0))
                self.corrections.put((header_stamp(stamped), Pose2D(float(tr["x"]), float(tr["y"]), yaw)))
            except (KeyError, TypeError, ValueError, AttributeError):
                continue

    def drain(self, watcher: Watcher) -> None:
        while not self.poses.empty():
            watcher.localiser(*self.poses.get())
        while not self.corrections.empty():
            t, map_odom = self.corrections.get()
            raw = self.driver.raw_odometry_at(t)
            if raw is not None:
                watcher.localiser(t, map_odom * raw)


def watch_live(
    cfg: SessionConfig,
    storey: str | None,
    pose_topic: str | None,
    duration: float = 0.0,
    echo: Callable[[WatchEvent], None] = lambda event: None,
) -> WatchResult:
    """Watch the robot of ``cfg`` (module docstring); the result when ``duration`` s passed."""
    with tempfile.TemporaryDirectory(prefix="bim-init-watch-") as tmp:
        site = prepare_site(cfg, Path(tmp))
    name = watched_storey(site, storey if storey is not None else cfg.site.storey)
    watcher = Watcher(site, name, cfg.watch, replace(cfg.registration, enabled=True), cfg.verification)
    r = cfg.robot.rosbridge
    with RosbridgeLink(r.host, r.port) as link:
        rb = cfg.robot
        drive = cfg.watch.drive
        driver = RosbridgeDriver(
            link,
            NO_CAMERA,
            NO_MOUNT,
            r,
            drive,
            max_linear=rb.max_linear,
            max_angular=rb.max_angular,
            camera_topics=False,
        )
        explorer = Explorer(cfg, driver) if drive else None
        feed = LocaliserFeed(link, driver, pose_topic or cfg.watch.pose_topic)
        link.advertise(STATE_TOPIC, STRING)
        link.advertise(DIAGNOSTICS_TOPIC, DIAGNOSTIC_ARRAY)
        driver.wait_odometry(r.camera_wait)
        driver.wait_laser(r.camera_wait)
        frame = driver.start()
        started, last_status, last_state = time.monotonic(), -math.inf, None
        while duration <= 0 or time.monotonic() - started < duration:
            stamp = driver.frame_stamp
            watcher.odom(stamp, frame.odom)
            feed.drain(watcher)
            if frame.scan is not None:
                scan = frame.scan
                for event in watcher.scan(stamp, scan.angles, np.asarray(scan.ranges, float), scan.range_max):
                    echo(event)
                    _act(cfg, link, driver, watcher, event, frame.odom, stamp)
            if watcher.state != last_state or time.monotonic() - last_status >= STATUS_PERIOD_S:
                _status(link, driver, watcher, stamp)
                last_state, last_status = watcher.state, time.monotonic()
            frame = explorer.step(frame, watcher.state) if explorer is not None else driver.step(0.0, 0.0)
        if explorer is not None:
            explorer.hand_back()
        link.flush()
    return WatchResult(
        name, watcher.events, watcher.checks, [], watcher.state, watcher.travel, watcher.why_not_recovered
    )


def _status(
    link: RosbridgeLink,
    driver: RosbridgeDriver,
    watcher: Watcher,
    stamp: float,
    state: WatchState | None = None,
) -> None:
    """The state on /bim_init/state and the diagnostics on /diagnostics (``state``: the watcher's)."""
    said = watcher.state if state is None else state
    link.publish(STATE_TOPIC, STRING, state_message(str(said)))
    link.publish(DIAGNOSTICS_TOPIC, DIAGNOSTIC_ARRAY, diagnostic_message(stamp, watcher, driver.ros1, said))


def _act(
    cfg: SessionConfig,
    link: RosbridgeLink,
    driver: RosbridgeDriver,
    watcher: Watcher,
    event: WatchEvent,
    odom: Pose2D,
    stamp: float,
) -> None:
    """Lost: said at once (a recovery may follow in the same check); recovered: sent to Nav2."""
    if event.kind is EventKind.LOST:
        _status(link, driver, watcher, stamp, WatchState.LOST)
    if event.kind is EventKind.RECOVERED and event.pose is not None:
        _deliver(cfg, driver, event.pose * odom.inverse(), stamp)


def _deliver(cfg: SessionConfig, driver: RosbridgeDriver, transform: Pose2D, stamp: float) -> dict[str, Any]:
    """Send the recovered pose to Nav2 (``transform``: odom -> map), carried forward by odometry."""
    sd, yaw_sd = RECOVERED_SD_M, math.radians(RECOVERED_SD_DEG)
    covariance = np.diag([sd**2, sd**2, yaw_sd**2])
    carried = CarriedPose(transform, covariance, stamp, driver.odometry, FilterNoise())
    return deliver_initial_pose(driver.link, carried, cfg.nav2, driver.ros1)
