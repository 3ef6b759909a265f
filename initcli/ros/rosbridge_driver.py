"""``robot.driver: rosbridge``: a real robot behind the :class:`~initcli.drivers.base.RobotDriver`
interface, over rosbridge.

It subscribes to the robot's odometry, laser scan, detections (``vision_msgs/Detection2DArray``,
the robot's own detector) and aligned depth image; each :meth:`step` sends the command as
``geometry_msgs/Twist`` on ``cmd_vel`` (``robot.drive: false``: nothing is sent, a person drives),
waits one control period and reports what arrived. The robot is stopped (a zero Twist) on any
error, on Ctrl-C and when the driver is closed. The session publishes its hypotheses
(``/bim_init/hypotheses``) and its state (``/bim_init/state``) through :meth:`publish_hypotheses`
and :meth:`publish_state`; the result goes out through :mod:`initcli.ros.delivery`.

Time: a frame's session time is the robot's clock (its odometry's ``header.stamp``) since the
first frame (:attr:`clock_origin`), so a logged pose is the odometry at its stamp; what is sent
is stamped on the robot's clock, ROS 1 style (``secs``/``nsecs``) when the robot stamps so.
"""

from __future__ import annotations

import base64
import math
import threading
import time
from collections import deque
from types import SimpleNamespace
from typing import Any

import numpy as np

from bimkit.errors import InputError
from initcli.core.geometry.depth import window_depth
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import LaserScan, SensorFrame
from initcli.io.detection_log import DetectedObject
from initcli.ros.bag_reader import DEPTH_SYNC_S
from initcli.ros.messages import decode_depth
from initcli.ros.msgdefs import bbox_centre, detection_fields
from initcli.ros.nav2 import pose_array_message, state_message
from initcli.ros.records import HYPOTHESES_TOPIC, POSE_ARRAY, STATE_TOPIC, STRING, TWIST
from initcli.ros.rosbridge import RosbridgeLink
from initcli.ros.tf import quaternion_yaw

__all__ = ["CONTROL_RATE", "ODOM_HISTORY", "ODOM_TIMEOUT_S", "RosbridgeDriver", "header_stamp", "json_depth"]

CONTROL_RATE = 10.0  # Hz
ODOM_TIMEOUT_S = 1.0  # s without odometry: the robot is stopped and the session ends
ODOM_HISTORY = 20000  # odometry messages kept (robot-clock stamp, pose): minutes at 50 Hz


def _ns(value: Any) -> Any:
    """rosbridge JSON -> attribute access (what the bag reader's helpers take)."""
    if isinstance(value, dict):
        return SimpleNamespace(**{k: _ns(v) for k, v in value.items()})
    if isinstance(value, list):
        return [_ns(v) for v in value]
    return value


def header_stamp(msg: dict[str, Any]) -> float:
    """A message's ``header.stamp`` in seconds, ROS 2 ``{sec, nanosec}`` or ROS 1 ``{secs, nsecs}``."""
    st = msg.get("header", {}).get("stamp", {})
    return float(st.get("sec", st.get("secs", 0))) + float(st.get("nanosec", st.get("nsecs", 0))) * 1e-9


def json_depth(msg: dict[str, Any]) -> np.ndarray:
    """A rosbridge depth Image (``data`` base64, as rosbridge sends uint8[]) -> metres."""
    data = msg.get("data", "")
    raw = base64.b64decode(data) if isinstance(data, str) else bytes(data)
    return decode_depth(SimpleNamespace(**{**msg, "data": raw}))


class RosbridgeDriver:
    """Commands out, sensors in, over one :class:`RosbridgeLink` (see the module docstring)."""

    control_rate = CONTROL_RATE

    def __init__(
        self,
        link: RosbridgeLink,
        camera: CameraIntrinsics,
        mount: CameraMount,
        topics: Any,  # initcli.config.RosbridgeSection
        drive: bool = True,
        depth_window: int = 2,
        max_linear: float = 0.5,
        max_angular: float = 1.0,
        odom_timeout: float = ODOM_TIMEOUT_S,
        period: float | None = None,
    ) -> None:
        self.link = link
        self.camera, self.mount = camera, mount
        self.topics = topics
        self.drive = drive
        self.depth_window = depth_window
        self.max_linear, self.max_angular = max_linear, max_angular
        self.odom_timeout = odom_timeout
        self.period = 1.0 / CONTROL_RATE if period is None else period
        self._lock = threading.Lock()
        self._odom: tuple[float, Pose2D] | None = None  # (arrival, pose in the robot's odom frame)
        self._odom_t = 0.0  # the newest odometry's stamp on the robot's clock
        self._history: deque[tuple[float, Pose2D]] = deque(maxlen=ODOM_HISTORY)
        self.ros1 = False  # the robot stamps ROS 1 style (secs, nsecs): so does what is sent
        self.wall_clock = False  # its odometry has no stamps: the robot's clock is taken as ours
        self.clock_origin: float | None = None  # robot-clock stamp of session time 0
        self.frame_stamp = 0.0  # robot-clock stamp of the last frame
        self.base_frame = ""  # the odometry's child frame (the robot's base), once it arrived
        self._scan: LaserScan | None = None
        self._detections: deque[dict[str, Any]] = deque(maxlen=20)
        self._depths: deque[tuple[float, dict[str, Any]]] = deque(maxlen=10)
        self._origin: Pose2D | None = None
        self._last: Pose2D | None = None
        self._distance = 0.0
        link.subscribe(topics.odom_topic, "nav_msgs/msg/Odometry", self._on_odom)
        link.subscribe(topics.scan_topic, "sensor_msgs/msg/LaserScan", self._on_scan)
        link.subscribe(topics.detections_topic, "vision_msgs/msg/Detection2DArray", self._on_detections)
        link.subscribe(topics.depth_topic, "sensor_msgs/msg/Image", self._on_depth)
        if drive:
            link.advertise(topics.cmd_vel_topic, TWIST)

    # -- subscriptions (roslibpy's thread) ----------------------------------------------------------

    def _on_odom(self, msg: dict[str, Any]) -> None:
        pose = msg["pose"]["pose"]
        p, q = pose["position"], pose["orientation"]
        yaw = quaternion_yaw(q.get("x", 0.0), q.get("y", 0.0), q.get("z", 0.0), q.get("w", 1.0))
        self.base_frame = self.base_frame or str(msg.get("child_frame_id") or "")
        stamp_fields = msg.get("header", {}).get("stamp", {})
        stamp = header_stamp(msg)
        if stamp <= 0.0:  # no stamp: the robot's clock is this machine's (rosbridge on the robot)
            stamp, self.wall_clock = time.time(), True
        pose2 = Pose2D(float(p.get("x", 0.0)), float(p.get("y", 0.0)), yaw)
        with self._lock:
            self.ros1 = self.ros1 or "secs" in stamp_fields
            self._odom = (time.monotonic(), pose2)
            self._odom_t = stamp
            self._history.append((stamp, pose2))

    def _on_scan(self, msg: dict[str, Any]) -> None:
        ranges = np.array([math.inf if r is None else float(r) for r in msg.get("ranges", [])])
        with self._lock:
            self._scan = LaserScan(
                float(msg["angle_min"]), float(msg["angle_increment"]), float(msg["range_max"]), ranges
            )

    def _on_detections(self, msg: dict[str, Any]) -> None:
        with self._lock:
            self._detections.append(msg)

    def _on_depth(self, msg: dict[str, Any]) -> None:
        with self._lock:
            self._depths.append((header_stamp(msg), msg))

    # -- RobotDriver --------------------------------------------------------------------------------

    @property
    def distance(self) -> float:
        return self._distance

    def _objects(self, msg: dict[str, Any]) -> list[DetectedObject] | None:
        t = header_stamp(msg)
        with self._lock:
            best = min(self._depths, key=lambda d: abs(d[0] - t), default=None)
        if best is None or abs(best[0] - t) > DEPTH_SYNC_S:
            return None
        depth = json_depth(best[1])
        out = []
        for det in _ns(msg).detections:
            hyps = detection_fields(det)
            if not hyps:
                continue
            cls, score = max(hyps, key=lambda h: h[1])
            cu, cv = bbox_centre(det.bbox)
            sx, sy = float(det.bbox.size_x), float(det.bbox.size_y)
            z = window_depth(depth, cu, cv, self.depth_window)  # Eq. 1: D at the box centre
            out.append(DetectedObject(cls, score, (cu - sx / 2, cv - sy / 2, cu + sx / 2, cv + sy / 2), z))
        return out

    def _frame(self) -> SensorFrame:
        with self._lock:
            odom = self._odom
            stamp = self._odom_t
            scan = self._scan
            pending = list(self._detections)
            self._detections.clear()
        if odom is None or time.monotonic() - odom[0] > self.odom_timeout:
            self.stop()
            raise InputError(
                f"rosbridge: no odometry on {self.topics.odom_topic} for {self.odom_timeout:.1f} s"
            )
        if self._origin is None:
            self._origin = odom[1].inverse()  # the odom frame starts at the current pose (§3.3.1)
            self.clock_origin = stamp
        pose = self._origin * odom[1]
        self.frame_stamp = stamp
        if self._last is not None:
            self._distance += pose.distance_to(self._last)
        self._last = pose
        detections = None
        for msg in pending:
            objects = self._objects(msg)
            if objects is not None:
                detections = (detections or []) + objects
        # Session time is the robot's clock since the start: a frame's pose is its odometry's, at its stamp.
        return SensorFrame(stamp - (self.clock_origin or stamp), pose, scan, detections)

    def wait_odometry(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for the first odometry; whether it came."""
        deadline = time.monotonic() + timeout
        while self._odom is None and time.monotonic() < deadline:
            time.sleep(0.01)
        return self._odom is not None

    def start(self) -> SensorFrame:
        self.wait_odometry(self.odom_timeout + 1.0)
        return self._frame()

    def step(self, v: float, w: float) -> SensorFrame:
        try:
            self.command(v, w)
            time.sleep(self.period)
            return self._frame()
        except BaseException:  # any error or Ctrl-C: stop the robot first
            self.stop()
            raise

    def command(self, v: float, w: float) -> None:
        if not self.drive:
            return
        v = float(np.clip(v, -self.max_linear, self.max_linear))
        w = float(np.clip(w, -self.max_angular, self.max_angular))
        self.link.publish(
            self.topics.cmd_vel_topic,
            TWIST,
            {"linear": {"x": v, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": w}},
        )

    def stop(self) -> None:
        """Send a zero Twist (ignoring a dead connection: there is nothing else to do)."""
        if not self.drive:
            return
        try:
            self.command(0.0, 0.0)
        except Exception:  # noqa: BLE001 - the link is gone; the robot's own watchdog must act
            pass

    # -- what the session publishes -----------------------------------------------------------------

    def publish_state(self, state: str) -> None:
        self.link.publish(STATE_TOPIC, STRING, state_message(state))

    def robot_stamp(self, t: float) -> float:
        """Session time ``t`` on the robot's clock."""
        return (self.clock_origin or 0.0) + t

    def odometry(self) -> list[tuple[float, Pose2D]]:
        """The odometry that arrived (robot-clock stamp, pose in the session's odom frame), oldest first."""
        with self._lock:
            history = list(self._history)
        origin = self._origin or Pose2D.identity()
        return [(t, origin * p) for t, p in history]

    def publish_hypotheses(self, t: float, poses: list[Pose2D]) -> None:
        """The hypotheses of the match step at session time ``t``, stamped on the robot's clock."""
        message = pose_array_message(self.robot_stamp(t), poses, ros1=self.ros1)
        self.link.publish(HYPOTHESES_TOPIC, POSE_ARRAY, message)

    def close(self) -> None:
        self.stop()
        self.link.close()

    def __enter__(self) -> RosbridgeDriver:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
