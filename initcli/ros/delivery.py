"""Getting the pose into Nav2 and knowing it got there (``nav2:`` settings).

:class:`CarriedPose` is the verified pose carried forward by odometry: the map<-odom transform
of the claim applied to the newest odometry, stamped with that odometry's robot-clock time, its
covariance grown by the odometry model's noise over the motion since the claim.

:func:`deliver_initial_pose` advertises ``/initialpose``, waits until rosbridge reports the
publisher (rosapi) or ``nav2.advertise_delay``, calls AMCL's ``set_initial_pose`` service where
rosbridge offers it, publishes, and re-publishes every ``nav2.confirm.republish_period`` until
AMCL's pose (``nav2.confirm.amcl_topic``) comes within the tolerance of ours or
``nav2.confirm.timeout`` passes; then it waits until rosbridge has read every frame sent (a
service round trip) before the link may close. The report goes into ``summary.json``.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np

from initcli.core.geometry.motion import Alphas, carry_covariance
from initcli.core.geometry.se2 import SESSION_DIGITS, Pose2D, pose_json
from initcli.ros.nav2 import covariance_6x6, initial_pose_message, state_message
from initcli.ros.records import (
    INITIALPOSE_TOPIC,
    POSE_WITH_COVARIANCE_STAMPED,
    STATE_TOPIC,
    STRING,
    InitialPose,
)
from initcli.ros.rosbridge import CONNECT_TIMEOUT_S, DEFAULT_PORT, RosbridgeLink
from initcli.ros.rosbridge_driver import header_stamp
from initcli.ros.tf import quaternion_yaw

__all__ = [
    "ADVERTISE_WAIT_S",
    "SERVICE_TIMEOUT_S",
    "CarriedPose",
    "FixedPose",
    "PoseSource",
    "deliver_initial_pose",
    "pose_record",
    "publish_initial_pose",
]

SERVICE_TIMEOUT_S = 2.0  # s: one rosapi / set_initial_pose call
ADVERTISE_WAIT_S = 5.0  # s: rosapi asked at most this long whether /initialpose is up
SET_INITIAL_POSE = "nav2_msgs/srv/SetInitialPose"

Odometry = Callable[[], Sequence[tuple[float, Pose2D]]]  # (robot-clock stamp, odom pose), oldest first


def pose_record(stamp: float, pose: Pose2D, covariance: np.ndarray | None = None) -> dict[str, Any]:
    """A pose with its robot-clock stamp, as ``summary.json`` keeps it."""
    doc: dict[str, Any] = {"stamp": round(stamp, 6), **pose_json(pose, SESSION_DIGITS)}
    if covariance is not None:
        doc["covariance"] = [[round(float(v), 8) for v in row] for row in covariance]
    return doc


class CarriedPose:
    """The claim's pose (``map_from_odom`` of the claim, its covariance, its stamp) carried forward
    by the robot's odometry (``odometry()``: what arrived, stamped on the robot's clock)."""

    def __init__(
        self,
        map_from_odom: Pose2D,
        covariance: np.ndarray | None,
        claim_stamp: float,
        odometry: Odometry,
        noise: Alphas,
    ) -> None:
        self.map_from_odom = map_from_odom
        self.covariance = None if covariance is None else np.asarray(covariance, dtype=float)
        self.claim_stamp = claim_stamp
        self.odometry = odometry
        self.noise = noise
        self.sent: tuple[float, Pose2D, np.ndarray | None] | None = None

    def _since_claim(self) -> list[tuple[float, Pose2D]]:
        history = list(self.odometry())
        before = [h for h in history if h[0] <= self.claim_stamp + 1e-6]
        after = [h for h in history if h[0] > self.claim_stamp + 1e-6]
        return before[-1:] + after

    def now(self) -> tuple[float, Pose2D, np.ndarray | None]:
        """(stamp, map pose, 3x3 covariance) at the newest odometry."""
        path = self._since_claim()
        if not path:
            raise RuntimeError("no odometry since the claim")
        poses = [self.map_from_odom * p for _, p in path]
        cov = None if self.covariance is None else carry_covariance(self.covariance, poses, self.noise)
        return path[-1][0], poses[-1], cov

    def at(self, stamp: float) -> Pose2D | None:
        """The carried pose at the odometry nearest ``stamp`` (None: no odometry within 0.2 s)."""
        history = list(self.odometry())
        if not history:
            return None
        near = min(history, key=lambda h: abs(h[0] - stamp))
        return self.map_from_odom * near[1] if abs(near[0] - stamp) <= 0.2 else None

    def message_pose(self) -> InitialPose:
        """The pose to send now (kept as :attr:`sent`: the last one asked for)."""
        stamp, pose, cov = self.now()
        self.sent = (stamp, pose, cov)
        return InitialPose(stamp, pose.x, pose.y, pose.yaw, covariance_6x6(cov))


class PoseSource(Protocol):
    """What :func:`deliver_initial_pose` sends: the pose to send now, and ours at a stamp."""

    def message_pose(self) -> InitialPose: ...
    def at(self, stamp: float) -> Pose2D | None: ...


class FixedPose:
    """A pose that is not carried (``bim-init publish-pose``: no odometry): the same each send."""

    def __init__(self, pose: InitialPose) -> None:
        self.pose = pose

    def message_pose(self) -> InitialPose:
        return self.pose

    def at(self, stamp: float) -> Pose2D | None:
        return Pose2D(self.pose.x, self.pose.y, self.pose.yaw)


def _amcl_pose(msg: dict[str, Any]) -> tuple[float, Pose2D]:
    pose = msg["pose"]["pose"]
    p, q = pose["position"], pose["orientation"]
    yaw = quaternion_yaw(q.get("x", 0.0), q.get("y", 0.0), q.get("z", 0.0), q.get("w", 1.0))
    return header_stamp(msg), Pose2D(float(p.get("x", 0.0)), float(p.get("y", 0.0)), yaw)


def _advertised(link: RosbridgeLink, delay: float) -> str:
    """Wait until rosbridge reports the /initialpose publisher: ``rosapi``; ``delay``: no rosapi,
    waited ``nav2.advertise_delay``; ``unconfirmed``: rosapi never listed it."""
    deadline = time.monotonic() + ADVERTISE_WAIT_S
    while time.monotonic() < deadline:
        up = link.publisher_up(INITIALPOSE_TOPIC, SERVICE_TIMEOUT_S)
        if up is None:
            time.sleep(delay)
            return "delay"
        if up:
            return "rosapi"
        time.sleep(0.05)
    return "unconfirmed"


def deliver_initial_pose(
    link: RosbridgeLink,
    carried: PoseSource,
    settings: Any,  # initcli.config.Nav2Section
    ros1: bool = False,
) -> dict[str, Any]:
    """Send the carried pose to Nav2 until AMCL takes it (see the module docstring); the report."""
    confirm = settings.confirm
    amcl: list[tuple[float, Pose2D]] = []
    arrived = threading.Event()

    def on_amcl(msg: dict[str, Any]) -> None:
        try:
            amcl.append(_amcl_pose(msg))
        except (KeyError, TypeError, ValueError):
            return
        arrived.set()

    if confirm.timeout > 0:
        link.subscribe(confirm.amcl_topic, POSE_WITH_COVARIANCE_STAMPED, on_amcl)
    link.advertise(INITIALPOSE_TOPIC, POSE_WITH_COVARIANCE_STAMPED)
    report: dict[str, Any] = {
        "topic": INITIALPOSE_TOPIC,
        "advertised": _advertised(link, settings.advertise_delay),
    }
    first = carried.message_pose()
    message = initial_pose_message(first, ros1)
    answer = link.call_service(
        settings.set_initial_pose_service, SET_INITIAL_POSE, {"pose": message}, SERVICE_TIMEOUT_S
    )
    report["set_initial_pose"] = (
        {"called": False, "answer": "no answer"}
        if answer is None
        else {"called": answer[0], "answer": answer[1] if answer[0] else str(answer[1])}
    )
    sends: list[float] = []
    start = time.monotonic()
    confirmed: dict[str, Any] | None = None
    pose = carried.message_pose()  # carried again: the service call may have taken a while
    while True:
        link.publish(INITIALPOSE_TOPIC, POSE_WITH_COVARIANCE_STAMPED, initial_pose_message(pose, ros1))
        sends.append(pose.stamp)
        period_end = time.monotonic() + confirm.republish_period
        while confirmed is None and time.monotonic() < min(period_end, start + confirm.timeout):
            arrived.wait(0.05)
            arrived.clear()
            confirmed = _agreement(amcl, carried, sends[0], confirm)
        if confirmed is not None or time.monotonic() >= start + confirm.timeout:
            break
        pose = carried.message_pose()
    report["sends"] = len(sends)
    report["sent_stamps"] = [round(s, 6) for s in sends]
    report["flushed"] = link.flush()
    if confirm.timeout <= 0:
        report["confirmed"] = None
    else:
        report["confirmed"] = confirmed is not None
        report["amcl_messages"] = len(amcl)
        if confirmed is not None:
            report |= confirmed | {"after_s": round(time.monotonic() - start, 3)}
    return report


def _agreement(
    amcl: list[tuple[float, Pose2D]], carried: PoseSource, first_sent: float, confirm: Any
) -> dict[str, Any] | None:
    """The first AMCL pose, stamped since our first send, within the tolerance of ours at its stamp."""
    for stamp, theirs in list(amcl):
        if stamp < first_sent - 1e-6:
            continue
        ours = carried.at(stamp)
        if ours is None:
            continue
        err_m, err_deg = ours.distance_to(theirs), math.degrees(ours.yaw_error(theirs))
        if err_m <= confirm.tolerance_m and err_deg <= confirm.tolerance_deg:
            return {
                "amcl_stamp": round(stamp, 6),
                "amcl_error_m": round(err_m, 4),
                "amcl_error_deg": round(err_deg, 3),
            }
    return None


def publish_initial_pose(
    pose: InitialPose,
    host: str = "localhost",
    port: int = DEFAULT_PORT,
    settings: Any = None,  # initcli.config.Nav2Section; None: its defaults without confirmation
    ros1: bool = False,
    timeout: float = CONNECT_TIMEOUT_S,
) -> dict[str, Any]:
    """``bim-init publish-pose``: deliver ``pose`` as it is (and "initialised" on the state topic);
    the delivery report, with the message sent as ``message``."""
    if settings is None:
        from initcli.config import Nav2Section

        settings = Nav2Section()
        settings.confirm.timeout = 0.0
    with RosbridgeLink(host, port, timeout) as link:
        link.advertise(STATE_TOPIC, STRING)
        report = deliver_initial_pose(link, FixedPose(pose), settings, ros1)
        link.publish(STATE_TOPIC, STRING, state_message("initialised"))
        report["flushed"] = report["flushed"] and link.flush()  # a server mute once is not asked again
    return report | {"message": initial_pose_message(pose, ros1)}
