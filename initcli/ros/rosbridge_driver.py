"""``robot.driver: rosbridge``: a real robot behind the :class:`~initcli.drivers.base.RobotDriver`
interface, over rosbridge.

It subscribes to the robot's odometry, laser scan, ``/tf_static``, detections
(``vision_msgs/Detection2DArray``, the robot's own detector) and aligned depth image (not the last
two on a robot without a camera: :meth:`RosbridgeDriver.listen_camera` is then never called); each
:meth:`step` sends the command as ``geometry_msgs/Twist`` on ``cmd_vel`` (``robot.drive: false``:
nothing is sent, a person drives), waits one control period and reports what arrived. The robot
is stopped (a zero Twist) on any error, on Ctrl-C and when the driver is closed. The session
publishes its hypotheses (``/bim_init/hypotheses``) and its state (``/bim_init/state``) through
:meth:`publish_hypotheses` and :meth:`publish_state`; the result goes out through
:mod:`initcli.ros.delivery`.

Scans: the LaserScan's ``frame_id`` is resolved through ``/tf_static`` to the base frame
(``robot.rosbridge.base_frame`` or the odometry's child frame) and each scan is carried into the
base frame (:func:`initcli.io.laser.scan_in_base`, any offset and yaw); inf, NaN (``null`` in
rosbridge's JSON), 0 and ranges outside [range_min, range_max) are no returns. A scan whose
geometry is broken (:func:`initcli.io.laser.check_scan_geometry`) is dropped, with one warning for
the first; a laser frame with no chain to the base in ``camera_wait`` s is taken as at the base
origin, facing ahead (one warning).

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
from collections.abc import Callable
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from bimkit.errors import InputError
from initcli.core.geometry.depth import window_depth
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import LaserScan, SensorFrame
from initcli.io.detection_log import DetectedObject
from initcli.io.laser import check_scan_geometry, no_returns, scan_in_base
from initcli.ros.bag_reader import DEPTH_SYNC_S, _planar
from initcli.ros.messages import checked_transform, decode_depth
from initcli.ros.msgdefs import bbox_centre, detection_fields
from initcli.ros.nav2 import pose_array_message, state_message
from initcli.ros.records import HYPOTHESES_TOPIC, POSE_ARRAY, STATE_TOPIC, STRING, TF_MESSAGE, TWIST
from initcli.ros.rosbridge import RosbridgeLink
from initcli.ros.tf import TransformTree, frame_name, quaternion_yaw

__all__ = [
    "CONTROL_RATE",
    "ODOM_HISTORY",
    "ODOM_TIMEOUT_S",
    "LaserMount",
    "RosbridgeDriver",
    "StaticTransforms",
    "header_stamp",
    "json_depth",
]

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


def _number(value: Any) -> float:
    """A JSON number; ``null`` (rosbridge's NaN and inf) as NaN."""
    return math.nan if value is None else float(value)


def _checked_scan(where: str, msg: dict[str, Any]) -> _RawScan:
    """A LaserScan message checked (:func:`initcli.io.laser.check_scan_geometry`, range_max), its
    no-returns NaN; InputError naming ``where`` when broken."""
    ranges = np.array([_number(r) for r in msg.get("ranges") or []], dtype=float)
    angle_min, increment = _number(msg.get("angle_min")), _number(msg.get("angle_increment"))
    angle_max = msg.get("angle_max", "absent")
    span = None if angle_max == "absent" else _number(angle_max) - angle_min
    check_scan_geometry(where, len(ranges), angle_min, increment, span)
    range_max = _number(msg.get("range_max"))
    if not (math.isfinite(range_max) and range_max > 0):
        raise InputError(f"{where}: a LaserScan's range_max is {range_max:g}")
    range_min = _number(msg.get("range_min", 0.0))
    range_min = range_min if math.isfinite(range_min) else 0.0
    frame = str((msg.get("header") or {}).get("frame_id") or "")
    return _RawScan(frame, angle_min, increment, range_max, no_returns(ranges, range_min, range_max))


class StaticTransforms:
    """``/tf_static`` as it arrives (latched: each subscriber is sent it once, so the driver holds
    the one subscription): the transform tree, under a lock; :attr:`changed` is set on each message."""

    def __init__(self, topic: str) -> None:
        self.topic = topic
        self.tree = TransformTree()
        self.changed = threading.Event()
        self._lock = threading.Lock()

    def on_message(self, msg: dict[str, Any]) -> None:
        with self._lock:
            for stamped in getattr(_ns(msg), "transforms", None) or []:
                try:
                    self.tree.add(checked_transform(self.topic, stamped))
                except (InputError, AttributeError, TypeError):
                    continue
        self.changed.set()

    def lookup(self, parent: str, child: str) -> tuple[np.ndarray, np.ndarray] | None:
        """Pose of ``child`` in ``parent`` (rotation, translation); None while not connected."""
        with self._lock:
            try:
                return self.tree.lookup(parent, child)
            except (InputError, KeyError):
                return None


@dataclass(frozen=True)
class LaserMount:
    """The laser's mount on the base (x, y, yaw; ``flipped``: upside down) and where it came from."""

    frame: str
    pose: Pose2D
    flipped: bool
    source: str  # "/tf_static <base> -> <frame>", "the base frame" or "none: ..."


@dataclass(frozen=True)
class _RawScan:
    """A LaserScan as it came, in its own frame (no-returns NaN)."""

    frame: str
    angle_min: float
    angle_increment: float
    range_max: float
    ranges: np.ndarray


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
        camera_topics: bool = True,
        warn: Callable[[str], None] = lambda line: None,
    ) -> None:
        """``camera_topics``: subscribe the detections and depth at once (False: only when
        :meth:`listen_camera` is called, never on a robot without a camera); ``warn`` gets one line
        for the first broken scan and for a laser frame with no /tf_static chain to the base."""
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
        self.warn = warn
        self.camera_absent = False  # set by the session: no camera, the scans alone
        self.static = StaticTransforms(topics.tf_static_topic)
        self._raw_scan: _RawScan | None = None
        self._converted: tuple[_RawScan, LaserScan | None] | None = None  # the last raw scan, carried
        self._scans_in = 0  # LaserScan messages that arrived
        self.scans_dropped = 0  # of those, broken ones (dropped)
        self.detections_dropped = 0  # Detection2Ds with a score or box no detector sends (dropped)
        self._mounts: dict[str, LaserMount] = {}  # laser frame -> its mount on the base
        # /tf_static is waited for this long before a laser frame without a chain to the base is
        # taken as at the base origin
        self._mount_deadline = time.monotonic() + float(getattr(topics, "camera_wait", 3.0))
        self._detections: deque[dict[str, Any]] = deque(maxlen=20)
        self._depths: deque[tuple[float, dict[str, Any]]] = deque(maxlen=10)
        self._origin: Pose2D | None = None
        self._last: Pose2D | None = None
        self._distance = 0.0
        link.subscribe(topics.odom_topic, "nav_msgs/msg/Odometry", self._on_odom)
        link.subscribe(topics.scan_topic, "sensor_msgs/msg/LaserScan", self._on_scan)
        link.subscribe(topics.tf_static_topic, TF_MESSAGE, self.static.on_message)
        self._camera_listening = False
        if camera_topics:
            self.listen_camera()
        if drive:
            link.advertise(topics.cmd_vel_topic, TWIST)

    def listen_camera(self) -> None:
        """Subscribe the robot's detections and aligned depth image (once)."""
        if self._camera_listening:
            return
        self._camera_listening = True
        self.link.subscribe(
            self.topics.detections_topic, "vision_msgs/msg/Detection2DArray", self._on_detections
        )
        self.link.subscribe(self.topics.depth_topic, "sensor_msgs/msg/Image", self._on_depth)

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
        with self._lock:
            self._scans_in += 1
            n = self._scans_in
        where = f"{self.topics.scan_topic} (message {n})"
        try:
            raw = _checked_scan(where, msg)
        except (InputError, KeyError, TypeError, ValueError, AttributeError) as exc:
            with self._lock:
                self.scans_dropped += 1
                first = self.scans_dropped == 1
            if first:
                text = str(exc) if isinstance(exc, InputError) else f"{where}: a broken LaserScan ({exc!r})"
                self.warn(f"{text}; such scans are dropped")
            return
        with self._lock:
            self._raw_scan = raw

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

    def _drop_detection(self, what: str) -> None:
        """A Detection2D no detector sends (a score outside [0, 1], a box of negative size or not
        finite) is dropped, the first with a warning: the session log holds what a log may hold."""
        self.detections_dropped += 1
        if self.detections_dropped == 1:
            self.warn(
                f"{self.topics.detections_topic}: a Detection2D with {what}; such detections are dropped"
            )

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
            if not (0.0 <= score <= 1.0 and min(sx, sy) >= 0.0 and all(map(math.isfinite, (cu, cv, sx, sy)))):
                self._drop_detection(f"score {score:g}, box {sx:g} x {sy:g} px at ({cu:g}, {cv:g})")
                continue
            z = window_depth(depth, cu, cv, self.depth_window)  # Eq. 1: D at the box centre
            out.append(DetectedObject(cls, score, (cu - sx / 2, cv - sy / 2, cu + sx / 2, cv + sy / 2), z))
        return out

    # -- the laser ---------------------------------------------------------------------------------

    @property
    def laser_base(self) -> str:
        """The base frame the scans are carried into."""
        return frame_name(self.topics.base_frame or self.base_frame or "base_link")

    def laser_mount(self, frame: str) -> LaserMount | None:
        """The mount of the laser frame ``frame`` on the base, from /tf_static; None while waiting
        for it (until ``camera_wait`` s after the driver started), then the base origin (warned)."""
        known = self._mounts.get(frame)
        if known is not None:
            return known
        base = self.laser_base
        if not frame or frame_name(frame) == base:
            mount = LaserMount(frame, Pose2D(0.0, 0.0, 0.0), False, "the base frame")
        else:
            found = self.static.lookup(base, frame)
            if found is not None:
                r, tr = found
                where = f"{self.topics.tf_static_topic} {base} -> {frame_name(frame)}"
                mount = LaserMount(frame, _planar(r, tr), bool(r[2, 2] < 0), where)
            elif time.monotonic() < self._mount_deadline:
                return None
            else:
                self.warn(
                    f"no {self.topics.tf_static_topic} chain {base} -> {frame_name(frame)} (the frame of "
                    f"{self.topics.scan_topic}): its scans are taken as from the base origin, facing ahead"
                )
                mount = LaserMount(frame, Pose2D(0.0, 0.0, 0.0), False, "none: taken as the base origin")
        self._mounts[frame] = mount
        return mount

    def wait_laser(self, timeout: float) -> LaserMount | None:
        """Wait up to ``timeout`` s for a scan and its laser's mount; the mount (None: no scan yet)."""
        deadline = time.monotonic() + timeout
        while True:
            with self._lock:
                raw = self._raw_scan
            if raw is not None:
                mount = self.laser_mount(raw.frame)
                if mount is not None:
                    return mount
            if time.monotonic() >= deadline:
                return None
            self.static.changed.wait(0.02)
            self.static.changed.clear()

    @property
    def lidar_mount(self) -> Pose2D | None:
        """The (first) laser's mount on the base, once known."""
        return next(iter(self._mounts.values())).pose if self._mounts else None

    def lidar_record(self) -> dict[str, Any]:
        """``summary.json``'s ``lidar``: the laser's frame and mount, where it came from, the scans
        dropped."""
        mount = next(iter(self._mounts.values()), None)
        out: dict[str, Any] = {
            "topic": self.topics.scan_topic,
            "base_frame": self.laser_base,
            "scans": self._scans_in,
            "scans_dropped": self.scans_dropped,
        }
        if mount is not None:
            p = mount.pose
            out |= {
                "frame": frame_name(mount.frame),
                "mount": {"x": round(p.x, 4), "y": round(p.y, 4), "yaw_deg": round(math.degrees(p.yaw), 3)},
                "flipped": mount.flipped,
                "mount_from": mount.source,
            }
        return out

    def _scan_in_base(self, raw: _RawScan | None) -> LaserScan | None:
        if raw is None:
            return None
        if self._converted is not None and self._converted[0] is raw:
            return self._converted[1]
        mount = self.laser_mount(raw.frame)
        if mount is None:  # its mount not known yet: no scan this period
            return None
        s = scan_in_base(
            0.0, raw.angle_min, raw.angle_increment, raw.range_max, raw.ranges, mount.pose, mount.flipped
        )
        scan = LaserScan(s.angle_min, s.angle_increment, s.range_max, np.asarray(s.ranges, dtype=float))
        self._converted = (raw, scan)
        return scan

    # -- frames -------------------------------------------------------------------------------------

    def _frame(self) -> SensorFrame:
        with self._lock:
            odom = self._odom
            stamp = self._odom_t
            raw = self._raw_scan
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
        scan = self._scan_in_base(raw)
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

    def raw_odometry_at(self, stamp: float) -> Pose2D | None:
        """The odometry as the robot sent it (its own odom frame) nearest ``stamp``, within 0.2 s."""
        with self._lock:
            history = list(self._history)
        if not history:
            return None
        t, pose = min(history, key=lambda h: abs(h[0] - stamp))
        return pose if abs(t - stamp) <= 0.2 else None

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
