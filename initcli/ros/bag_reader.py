"""A recorded ROS bag (ROS 1 ``.bag``, ROS 2 ``.db3`` folder or ``.mcap``) -> detection-log records.

A bag without a camera (a LaserScan and odometry only) gives a log of odometry and scans whose meta
says ``camera_absent``. Scans are carried into the base frame from the laser's frame through
``/tf_static`` (any offset and yaw; :mod:`initcli.io.laser`); inf, NaN, 0 and ranges outside
[range_min, range_max) are no returns.

No ROS installation: rosbags reads the bag. The topics are chosen by message type when the bag
holds exactly one of a kind, otherwise by the options (:mod:`initcli.ros.bag_topics`). Each colour
image (run through the ONNX detector) or ``Detection2DArray`` becomes a ``detections`` record: the
box centre's depth is the window mean of Eq. 1 in the aligned depth image nearest in time, the pose
is the odometry interpolated at the image stamp, re-based so the log's odom frame starts at the
first pose (§3.3.1). ``CameraInfo`` gives the intrinsics and ``/tf_static`` the camera mount (base
frame -> optical frame).
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bimkit.errors import InputError
from initcli.core.geometry.depth import window_depth
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, mount_from_optical
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.io.detection_log import DetectedObject, Detections, Localiser, Meta, Odom, Record, Scan
from initcli.io.laser import check_odometry, check_scan_geometry, no_returns, scan_in_base
from initcli.io.log_records import NO_CAMERA, NO_MOUNT
from initcli.ros.bag_localiser import localiser_records
from initcli.ros.bag_source import BagSource
from initcli.ros.bag_topics import choose_topics
from initcli.ros.messages import (
    checked_transform,
    decode_depth,
    decode_image,
    finite,
    intrinsics,
    stamp_seconds,
)
from initcli.ros.msgdefs import bbox_centre, detection_fields
from initcli.ros.records import Bag2LogOptions, Bag2LogStats, BagTopics, Topic
from initcli.ros.tf import TransformTree, frame_name, quaternion_yaw

__all__ = [
    "BagSource",
    "CLOCK_JUMP_S",
    "DEPTH_BUFFER",
    "DEPTH_SYNC_S",
    "ODOM_MARGIN_S",
    "Progress",
    "bag_to_records",
    "decode_depth",
    "decode_image",
    "intrinsics",
    "parse_class_names",
    "stamp_seconds",
]

DEPTH_SYNC_S = 0.05  # s: a depth image this close in time to a colour image is its aligned one
ODOM_MARGIN_S = 0.2  # s: images this far outside the odometry's time span still get its end pose
CLOCK_JUMP_S = 0.5  # s: a topic whose stamps go back by more than this has a broken clock
DEPTH_BUFFER = 30  # depth images kept while waiting for their colour image

Progress = Callable[[int, int], None]  # (messages done, messages in all)


# --- message contents ------------------------------------------------------------------------------


@dataclass
class _Trajectory:
    """Planar base poses over time, interpolated at image stamps."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray  # unwrapped

    @staticmethod
    def of(samples: list[tuple[float, Pose2D]]) -> _Trajectory:
        samples.sort(key=lambda s: s[0])
        t = np.array([s[0] for s in samples])
        return _Trajectory(
            t,
            np.array([s[1].x for s in samples]),
            np.array([s[1].y for s in samples]),
            np.unwrap(np.array([s[1].yaw for s in samples])),
        )

    def at(self, t: float) -> Pose2D | None:
        if t < self.t[0] - ODOM_MARGIN_S or t > self.t[-1] + ODOM_MARGIN_S:
            return None
        return Pose2D(
            float(np.interp(t, self.t, self.x)),
            float(np.interp(t, self.t, self.y)),
            float(wrap_angle(float(np.interp(t, self.t, self.yaw)))),
        )


def _check_clock(topic: str, times: list[float]) -> None:
    for i in range(1, len(times)):
        if times[i] < times[i - 1] - CLOCK_JUMP_S:
            raise InputError(
                f"{topic}: the clock jumps back by {times[i - 1] - times[i]:.3f} s at message {i + 1} "
                f"({times[i - 1]:.3f} -> {times[i]:.3f} s); split the bag at the jump"
            )


def _planar(r: np.ndarray, t: np.ndarray) -> Pose2D:
    return Pose2D(float(t[0]), float(t[1]), math.atan2(r[1, 0], r[0, 0]))


def _class_namer(class_names: tuple[str, ...] | dict[str, str] | None) -> Callable[[str], str]:
    if class_names is None:
        return lambda c: c
    table = (
        {str(i): n for i, n in enumerate(class_names)}
        if isinstance(class_names, tuple)
        else {str(k).strip(): v for k, v in class_names.items()}
    )
    return lambda c: table.get(c.strip(), c)


def parse_class_names(text: str | None) -> tuple[str, ...] | dict[str, str] | None:
    """``door,lift,stairs`` (ids 0, 1, 2 in order) or ``0=door,1=lift,5=stairs``."""
    if text is None or not text.strip():
        return None
    parts = [p.strip() for p in text.split(",") if p.strip()]
    if all("=" in p for p in parts):
        return {k.strip(): v.strip() for k, v in (p.split("=", 1) for p in parts)}
    if any("=" in p for p in parts):
        raise InputError(f"--class-names: use either door,lift,stairs or 0=door,1=lift, got {text!r}")
    return tuple(parts)


# --- the conversion --------------------------------------------------------------------------------


class _Perceiver:
    """One perception message + its depth image -> detection-log objects."""

    def __init__(self, kind: str, options: Bag2LogOptions, stats: Bag2LogStats, topic: str = "") -> None:
        self.kind = kind
        self.topic = topic
        self.options = options
        self.stats = stats
        self.name = _class_namer(options.class_names)
        self.detector = None
        self.numeric_warned = False
        if kind != "detections":
            from initcli.detector.runtime import Detector

            self.detector = Detector(options.model, conf=options.score_threshold, threads=options.threads)

    def boxes(self, msg: Any) -> list[tuple[str, float, tuple[float, float, float, float]]]:
        if self.detector is not None:
            image = decode_image(msg)
            return [(d.class_name, float(d.score), d.box) for d in self.detector.detect(image)]
        out = []
        for det in msg.detections:
            hyps = detection_fields(det)
            if not hyps:
                continue
            cls, score = max(hyps, key=lambda h: h[1])
            if cls.strip().isdigit() and self.options.class_names is None and not self.numeric_warned:
                self.stats.warnings.append(
                    f"numeric class ids (e.g. {cls!r}) kept as they are; "
                    "map them with --class-names door,lift,stairs"
                )
                self.numeric_warned = True
            cu, cv = bbox_centre(det.bbox)
            sx, sy = float(det.bbox.size_x), float(det.bbox.size_y)
            finite(self.topic, "a Detection2D (bbox or score)", cu, cv, sx, sy, score)
            if not 0.0 <= score <= 1.0:
                raise InputError(f"{self.topic}: a Detection2D score of {score:g} is outside [0, 1]")
            if sx < 0 or sy < 0:
                raise InputError(f"{self.topic}: a Detection2D box of size {sx:g} x {sy:g} px (negative)")
            out.append((self.name(cls), score, (cu - sx / 2, cv - sy / 2, cu + sx / 2, cv + sy / 2)))
        return out

    def objects(self, msg: Any, depth: np.ndarray) -> tuple[DetectedObject, ...]:
        out = []
        n = self.options.depth_window
        for cls, score, (u1, v1, u2, v2) in self.boxes(msg):
            z = window_depth(depth, (u1 + u2) / 2.0, (v1 + v2) / 2.0, n)  # Eq. 1: D at the box centre
            out.append(
                DetectedObject(
                    cls,
                    round(score, 4),
                    (round(u1, 2), round(v1, 2), round(u2, 2), round(v2, 2)),
                    None if z is None else round(z, 4),
                )
            )
        return tuple(out)


def bag_to_records(
    path: Path | str, options: Bag2LogOptions | None = None, progress: Progress | None = None
) -> tuple[list[Record], Bag2LogStats]:
    """Read a bag into detection-log records (the :class:`Meta` first, then in time order)."""
    options = options or Bag2LogOptions()
    if options.rate is not None and options.rate <= 0:
        raise InputError(f"--rate must be positive, got {options.rate}")
    started = time.perf_counter()
    stats = Bag2LogStats()
    path = Path(path)
    with BagSource(path) as source:
        topics = choose_topics(source, options)
        tick = _Ticker(topics, stats, progress)
        first = _FirstPass.read(source, topics, tick)  # everything but the images
        camera, optical_frame = NO_CAMERA, ""
        if topics.camera_info is not None:
            if first.camera_msg is None:
                raise InputError(f"{topics.camera_info.name}: no CameraInfo message in the bag")
            camera = intrinsics(first.camera_msg, topics.camera_info.name)
            optical_frame = frame_name(first.camera_msg.header.frame_id)
        base, odom_samples = _base_odometry(first, topics, options)
        mount: CameraMount = NO_MOUNT
        if topics.camera_info is not None:
            rotation, translation = first.tree.lookup(base, optical_frame)
            mount = mount_from_optical(rotation, translation)
        trajectory = _Trajectory.of(odom_samples)
        check_odometry(
            _odometry_name(topics, base), trajectory.t.tolist(), np.column_stack([trajectory.x, trajectory.y])
        )
        origin = Pose2D(float(trajectory.x[0]), float(trajectory.y[0]), float(trajectory.yaw[0])).inverse()

        records: list[Odom | Scan | Detections | Localiser] = []  # each with a time stamp t
        for i in range(len(trajectory.t)):
            p = origin * Pose2D(float(trajectory.x[i]), float(trajectory.y[i]), float(trajectory.yaw[i]))
            records.append(Odom(float(trajectory.t[i]), p.x, p.y, float(wrap_angle(p.yaw))))
        stats.odom = len(trajectory.t)
        scans, lidar_mount = first.scans_in_base(base)
        records.extend(scans)
        stats.scans = len(scans)
        localiser = localiser_records(first.localiser, first.tf_edges, trajectory.at, topics, options)
        records.extend(localiser)
        stats.localiser = len(localiser)
        if topics.perception is not None:
            # Pass 2: perception, each with the depth image nearest in time.
            _PerceptionPass(topics, options, stats, camera, trajectory, origin, records).read(source, tick)
        if progress is not None:
            progress(tick.total, tick.total)

    if topics.perception is None:
        stats.camera_absent = True
        if not scans:
            assert topics.scan is not None
            raise InputError(f"{path}: no camera, and no message on {topics.scan.name}")
        what = f"no camera, {topics.scan.name if topics.scan else 'no scan'}"
    else:
        _check_images(path, topics, stats)
        what = topics.perception.name
    records.sort(key=lambda r: r.t)
    meta = Meta(
        camera=camera,
        camera_pose=mount,
        depth_window=None if stats.camera_absent else options.depth_window,
        source=f"bim-init bag2log {path.name} ({what}, base frame {base})",
        camera_absent=stats.camera_absent,
        lidar_mount=lidar_mount,
    )
    stats.seconds = time.perf_counter() - started
    return [meta, *records], stats


def _odometry_name(topics: BagTopics, base: str) -> str:
    return topics.odom.name if topics.odom is not None else f"/tf odom -> {base}"


class _Ticker:
    """Counts the messages read; ``progress(done, total)`` every 50."""

    def __init__(self, topics: BagTopics, stats: Bag2LogStats, progress: Progress | None) -> None:
        self.stats = stats
        self.progress = progress
        self.done = 0
        self.total = sum(
            t.count
            for t in (
                topics.perception,
                topics.depth,
                topics.camera_info,
                topics.odom,
                topics.tf,
                topics.tf_static,
                topics.scan,
            )
            if t is not None
        )

    def __call__(self) -> None:
        self.done += 1
        self.stats.messages += 1
        if self.progress is not None and self.done % 50 == 0:
            self.progress(self.done, self.total)


@dataclass
class _FirstPass:
    """Pass 1 over a bag: everything but the images (camera info, transforms, odometry, scans)."""

    topics: BagTopics
    tree: TransformTree = field(default_factory=TransformTree)
    camera_msg: Any = None  # the first CameraInfo
    odom_samples: list[tuple[float, Pose2D]] = field(default_factory=list)  # from the odometry topic
    odom_child: str | None = None  # the odometry's child frame
    tf_edges: list[tuple[float, str, str, Pose2D]] = field(default_factory=list)  # t, parent, child, pose
    scans: list[_RawScan] = field(default_factory=list)
    clock: dict[str, list[float]] = field(default_factory=dict)  # stamps per topic
    odom_children: set[str] = field(default_factory=set)  # every child frame the odometry named
    localiser: list[tuple[float, str, Pose2D]] = field(default_factory=list)  # t, frame, pose

    @staticmethod
    def read(source: BagSource, topics: BagTopics, tick: Callable[[], None]) -> _FirstPass:
        """Read pass 1; InputError when a topic's clock jumps back."""
        first = _FirstPass(topics)
        wanted = (topics.camera_info, topics.odom, topics.tf, topics.tf_static, topics.scan, topics.localiser)
        for name, bag_ns, msg in source.messages([t.name for t in wanted if t]):
            tick()
            first.add(name, bag_ns, msg)
        for name, times in first.clock.items():
            _check_clock(name, times)
        return first

    def add(self, name: str, bag_ns: int, msg: Any) -> None:
        topics = self.topics
        if topics.camera_info is not None and name == topics.camera_info.name:
            if self.camera_msg is None:
                self.camera_msg = msg
            return
        if topics.tf_static is not None and name == topics.tf_static.name:
            for tr in msg.transforms:
                self.tree.add(checked_transform(name, tr))
            return
        if topics.tf is not None and name == topics.tf.name:
            for tr in msg.transforms:
                e = checked_transform(name, tr)
                self.tf_edges.append(
                    (stamp_seconds(tr, bag_ns), e.parent, e.child, _planar(e.rotation, e.translation))
                )
            return
        t = stamp_seconds(msg, bag_ns)
        self.clock.setdefault(name, []).append(t)
        if topics.odom is not None and name == topics.odom.name:
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            finite(name, "an Odometry pose", p.x, p.y, q.x, q.y, q.z, q.w)
            self.odom_samples.append((t, Pose2D(float(p.x), float(p.y), quaternion_yaw(q.x, q.y, q.z, q.w))))
            child = frame_name(msg.child_frame_id)
            self.odom_child = child or self.odom_child
            if child:
                self.odom_children.add(child)
        elif topics.localiser is not None and name == topics.localiser.name:
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            finite(name, "a localiser pose", p.x, p.y, q.x, q.y, q.z, q.w)
            pose = Pose2D(float(p.x), float(p.y), quaternion_yaw(q.x, q.y, q.z, q.w))
            self.localiser.append((t, frame_name(msg.header.frame_id), pose))
        elif topics.scan is not None and name == topics.scan.name:
            where = f"{name} (message {len(self.scans) + 1}, t={t:.3f} s)"
            finite(
                where,
                "a LaserScan's angles or range_max",
                msg.angle_min,
                msg.angle_max,
                msg.angle_increment,
                msg.range_max,
            )
            ranges = np.asarray(msg.ranges, dtype=float)
            span = float(msg.angle_max) - float(msg.angle_min)
            check_scan_geometry(where, len(ranges), float(msg.angle_min), float(msg.angle_increment), span)
            range_max = float(msg.range_max)
            if range_max <= 0:
                raise InputError(f"{where}: a LaserScan's range_max is {range_max:g}")
            range_min = float(msg.range_min) if math.isfinite(float(msg.range_min)) else 0.0
            self.scans.append(
                _RawScan(
                    t,
                    frame_name(msg.header.frame_id),
                    float(msg.angle_min),
                    float(msg.angle_increment),
                    range_max,
                    no_returns(ranges, range_min, range_max),  # inf, NaN, 0, out of range: no return
                )
            )

    def scans_in_base(self, base: str) -> tuple[list[Scan], Pose2D | None]:
        """The scans carried into the base frame (each laser frame's mount from /tf_static), and the
        mount of the (first) laser (None: no scans)."""
        mounts: dict[str, tuple[Pose2D, bool]] = {}
        out = []
        for s in self.scans:
            if s.frame not in mounts:
                if not s.frame or s.frame == base:
                    mounts[s.frame] = (Pose2D(0.0, 0.0, 0.0), False)
                else:
                    r, tr = self.tree.lookup(base, s.frame)
                    mounts[s.frame] = (_planar(r, tr), bool(r[2, 2] < 0))
            mount, flipped = mounts[s.frame]
            out.append(
                scan_in_base(s.t, s.angle_min, s.angle_increment, s.range_max, s.ranges, mount, flipped)
            )
        first = mounts[self.scans[0].frame][0] if self.scans else None
        return out, first


@dataclass
class _RawScan:
    """A LaserScan as read, in its own frame (no-returns NaN)."""

    t: float
    frame: str
    angle_min: float
    angle_increment: float
    range_max: float
    ranges: np.ndarray


def _base_odometry(
    first: _FirstPass, topics: BagTopics, options: Bag2LogOptions
) -> tuple[str, list[tuple[float, Pose2D]]]:
    """The robot's base frame and its odometry poses over time (from the odometry topic, carried to
    the base frame, or from the /tf odom -> base transforms)."""
    base = frame_name(options.base_frame) if options.base_frame else None
    if topics.odom is None:
        return _tf_odometry(first, base)
    if not first.odom_samples:
        raise InputError(f"{topics.odom.name}: no odometry message")
    if len(first.odom_children) > 1:
        raise InputError(
            f"{topics.odom.name}: odometry of {len(first.odom_children)} child frames "
            f"({', '.join(sorted(first.odom_children))}): two publishers interleaved? use --odom-topic "
            "with a topic of one"
        )
    base = base or first.odom_child or "base_link"
    odom_child = first.odom_child
    if odom_child and odom_child != base:  # odometry of another frame: carry it to the base
        r, tr = first.tree.lookup(odom_child, base)
        offset = _planar(r, tr)
        return base, [(t, p * offset) for t, p in first.odom_samples]
    return base, first.odom_samples


def _tf_odometry(first: _FirstPass, base: str | None) -> tuple[str, list[tuple[float, Pose2D]]]:
    """The base frame (the one child of odom unless given) and its odom -> base transforms on /tf."""
    children = sorted({c for _, parent, c, _ in first.tf_edges if parent == "odom"})
    if base is None:
        if len(children) != 1:
            raise InputError(
                f"/tf: cannot tell the base frame (children of odom: {', '.join(children) or 'none'}); "
                "use --base-frame"
            )
        base = children[0]
    samples = [(t, p) for t, parent, c, p in first.tf_edges if c == base and parent == "odom"]
    if not samples:
        raise InputError(f"/tf: no odom -> {base} transform; use --base-frame or --odom-topic")
    _check_clock(f"/tf odom -> {base}", [t for t, _ in samples])
    return base, samples


class _PerceptionPass:
    """Pass 2 over a bag: each perception message (at most ``--rate`` often) with the depth image
    nearest in time, at the odometry pose of its stamp, appended to ``records`` as detections."""

    def __init__(
        self,
        topics: BagTopics,
        options: Bag2LogOptions,
        stats: Bag2LogStats,
        camera: CameraIntrinsics,
        trajectory: _Trajectory,
        origin: Pose2D,
        records: list[Odom | Scan | Detections | Localiser],
    ) -> None:
        self.topics = topics
        self.options = options
        self.stats = stats
        self.camera = camera
        self.trajectory = trajectory
        self.origin = origin
        self.records = records
        assert topics.perception is not None and topics.depth is not None
        self.perception: Topic = topics.perception
        self.depth: Topic = topics.depth
        self.perceiver = _Perceiver(topics.perception_kind, options, stats, topics.perception.name)
        self.depths: deque[tuple[float, Any]] = deque(maxlen=DEPTH_BUFFER)
        self.pending: deque[tuple[float, Any]] = deque()

    def read(self, source: BagSource, tick: Callable[[], None]) -> None:
        options, depths, pending = self.options, self.depths, self.pending
        last_kept = -math.inf
        perception, depth_topic = self.perception.name, self.depth.name
        seen: dict[str, list[float]] = {perception: [], depth_topic: []}
        for name, bag_ns, msg in source.messages([perception, depth_topic]):
            tick()
            t = stamp_seconds(msg, bag_ns)
            seen[name].append(t)
            if name == depth_topic:
                depths.append((t, msg))
            else:
                if options.rate is not None and t - last_kept < 1.0 / options.rate - 1e-9:
                    self.stats.skipped_rate += 1
                    continue
                last_kept = t
                pending.append((t, msg))
            latest = depths[-1][0] if depths else -math.inf
            while pending and latest >= pending[0][0]:
                self.resolve(*pending.popleft())
            while pending and len(depths) == depths.maxlen and depths[0][0] > pending[0][0] + DEPTH_SYNC_S:
                self.resolve(*pending.popleft())
        while pending:
            self.resolve(*pending.popleft())
        for name, times in seen.items():
            _check_clock(name, times)

    def resolve(self, item_t: float, msg: Any) -> None:
        """One perception message with the buffered depth image nearest in time (or counted as
        without depth / outside the odometry)."""
        stats, camera = self.stats, self.camera
        best = min(self.depths, key=lambda d: abs(d[0] - item_t), default=None)
        if best is None or abs(best[0] - item_t) > DEPTH_SYNC_S:
            stats.without_depth += 1
            return
        pose = self.trajectory.at(item_t)
        if pose is None:
            stats.outside_odometry += 1
            return
        depth = decode_depth(best[1])
        if depth.shape != (camera.height, camera.width):
            raise InputError(
                f"{self.depth.name}: depth image {depth.shape[1]}x{depth.shape[0]} is not aligned "
                f"with the colour camera ({camera.width}x{camera.height})"
            )
        objects = self.perceiver.objects(msg, depth)
        local = self.origin * pose
        pose_local = Pose2D(local.x, local.y, float(wrap_angle(local.yaw)))
        self.records.append(Detections(item_t, pose_local, objects))
        stats.images += 1
        stats.objects += len(objects)
        stats.objects_without_depth += sum(o.depth is None for o in objects)


def _check_images(path: Path, topics: BagTopics, stats: Bag2LogStats) -> None:
    """No image converted is bad input (saying why); images skipped are warnings."""
    assert topics.perception is not None and topics.depth is not None
    if stats.images == 0:
        if stats.without_depth:
            raise InputError(
                f"{path}: {stats.without_depth} image(s) from {topics.perception.name} and none with "
                f"an aligned "
                f"depth image from {topics.depth.name} within {DEPTH_SYNC_S} s"
            )
        if stats.outside_odometry:
            raise InputError(f"{path}: no image falls inside the odometry's time span")
        raise InputError(f"{path}: no image on {topics.perception.name}")
    if stats.without_depth:
        stats.warnings.append(f"{stats.without_depth} image(s) without an aligned depth image skipped")
    if stats.objects and stats.objects_without_depth == stats.objects:
        stats.warnings.append(
            f"none of the {stats.objects} detections has a depth ({topics.depth.name} holds no valid value "
            "at any box centre: NaN, 0 or out of range); bim-init match cannot place them"
        )
    if stats.outside_odometry:
        stats.warnings.append(f"{stats.outside_odometry} image(s) outside the odometry's time span skipped")
