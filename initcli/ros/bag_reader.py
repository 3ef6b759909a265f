"""A recorded ROS bag (ROS 1 ``.bag``, ROS 2 ``.db3`` folder or ``.mcap``) -> detection-log records.

No ROS installation: rosbags reads the bag. The topics are chosen by message type when the bag
holds exactly one of a kind (colour and depth images told apart by their encoding), otherwise by
the options. Each colour image (run through the ONNX detector) or ``Detection2DArray`` becomes a
``detections`` record: the box centre's depth is the window mean of Eq. 1 in the aligned depth
image nearest in time, the pose is the odometry interpolated at the image stamp, re-based so the
log's odom frame starts at the first pose (§3.3.1). ``CameraInfo`` gives the intrinsics and
``/tf_static`` the camera mount (base frame -> optical frame).
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bimkit.documents import check_regular
from bimkit.errors import InputError
from bimkit.limits import MAX_BAG_BYTES
from initcli.core.depth import window_depth
from initcli.core.geometry import Pose2D, wrap_angle
from initcli.core.projection import CameraMount, mount_from_optical
from initcli.io.detection_log import DetectedObject, Detections, Meta, Odom, Record, Scan
from initcli.ros.messages import (
    checked_transform,
    decode_depth,
    decode_image,
    finite,
    intrinsics,
    stamp_seconds,
)
from initcli.ros.msgdefs import bbox_centre, detection_fields, register_missing, ros2_typestore
from initcli.ros.records import (
    CAMERA_INFO,
    COMPRESSED_IMAGE,
    DEPTH_ENCODINGS,
    DETECTION_2D_ARRAY,
    IMAGE,
    LASER_SCAN,
    ODOMETRY,
    TF_MESSAGE,
    Bag2LogOptions,
    Bag2LogStats,
    BagTopics,
    Topic,
)
from initcli.ros.tf import TransformTree, frame_name, quaternion_yaw

DEPTH_SYNC_S = 0.05  # s: a depth image this close in time to a colour image is its aligned one
ODOM_MARGIN_S = 0.2  # s: images this far outside the odometry's time span still get its end pose
CLOCK_JUMP_S = 0.5  # s: a topic whose stamps go back by more than this has a broken clock
DEPTH_BUFFER = 30  # depth images kept while waiting for their colour image

Progress = Callable[[int, int], None]  # (messages done, messages in all)


# --- opening ---------------------------------------------------------------------------------------


def bag_paths(path: Path) -> list[Path]:
    """What rosbags opens for ``path``: a ROS 1 .bag, a ROS 2 bag folder or a bare .mcap file."""
    if not path.exists():
        raise InputError(f"{path}: no such bag")
    if path.is_file() and path.suffix == ".db3":
        return [path.parent]  # a ROS 2 sqlite3 file: its folder holds the metadata
    if path.is_dir() and not (path / "metadata.yaml").exists():
        mcaps = sorted(path.glob("*.mcap"))
        if len(mcaps) == 1:
            return mcaps
        raise InputError(f"{path}: a folder without metadata.yaml; expected a ROS 2 bag folder")
    if not path.is_dir():
        check_regular(path, "a ROS bag (.bag, .mcap or .db3)", MAX_BAG_BYTES)
    return [path]


class BagSource:
    """An open bag: its topics, and its messages deserialised (definitions registered if missing)."""

    def __init__(self, path: Path | str) -> None:
        from rosbags.highlevel import AnyReader

        self.path = Path(path)
        try:
            self.reader = AnyReader(bag_paths(self.path), default_typestore=ros2_typestore())
            self.reader.open()
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001 - rosbags raises many types for a bad file
            raise InputError(f"{self.path}: not a readable ROS bag ({_first_line(exc)})") from None
        register_missing(self.reader.typestore, {c.msgtype for c in self.reader.connections})
        self.topics: dict[str, Topic] = {}
        for c in self.reader.connections:
            old = self.topics.get(c.topic)
            self.topics[c.topic] = Topic(c.topic, c.msgtype, (old.count if old else 0) + c.msgcount)

    def close(self) -> None:
        self.reader.close()

    def __enter__(self) -> BagSource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.topics.values())

    def messages(self, topics: Iterable[str]) -> Iterator[tuple[str, int, Any]]:
        """(topic, bag time ns, message) in bag time order."""
        wanted = set(topics)
        conns = [c for c in self.reader.connections if c.topic in wanted]
        if not conns:
            return
        try:
            for conn, stamp, raw in self.reader.messages(connections=conns):
                yield conn.topic, stamp, self.reader.deserialize(raw, conn.msgtype)
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001
            raise InputError(f"{self.path}: cannot read a message ({_first_line(exc)})") from None

    def first(self, topic: str) -> Any | None:
        for _, _, msg in self.messages([topic]):
            return msg
        return None


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


# --- choosing topics -------------------------------------------------------------------------------


def _listing(topics: Iterable[Topic]) -> str:
    return "; ".join(t.describe() for t in topics) or "none"


def _pick(
    source: BagSource, given: str | None, types: tuple[str, ...], what: str, flag: str, required: bool
) -> Topic | None:
    if given is not None:
        topic = source.topics.get(given)
        if topic is None:
            raise InputError(
                f"{source.path}: no topic {given} ({flag}); the bag has: {_listing(source.topics.values())}"
            )
        if topic.msgtype not in types:
            raise InputError(f"{given} is {topic.msgtype}, {flag} needs {' or '.join(types)}")
        return topic
    found = [t for t in source.topics.values() if t.msgtype in types]
    if len(found) == 1:
        return found[0]
    if not found:
        if required:
            raise InputError(
                f"{source.path}: no {what} topic ({' or '.join(types)}); the bag has: "
                f"{_listing(source.topics.values())}"
            )
        return None
    raise InputError(f"{source.path}: several {what} topics, choose one with {flag}: {_listing(found)}")


def _encoding(source: BagSource, topic: Topic) -> str:
    msg = source.first(topic.name)
    return str(getattr(msg, "encoding", "")) if msg is not None else ""


def choose_topics(source: BagSource, options: Bag2LogOptions) -> BagTopics:
    """The topics to read; InputError naming the candidates when the choice is not clear."""
    if options.image_topic and options.detections_topic:
        raise InputError("give --image-topic or --detections-topic, not both")
    images = [t for t in source.topics.values() if t.msgtype == IMAGE]
    encodings = {t.name: _encoding(source, t) for t in images}
    depth_like = [t for t in images if encodings[t.name] in DEPTH_ENCODINGS]
    colour_like = [t for t in images if encodings[t.name] not in DEPTH_ENCODINGS]

    if options.depth_topic is not None:
        depth = _pick(source, options.depth_topic, (IMAGE,), "depth image", "--depth-topic", True)
    elif len(depth_like) == 1:
        depth = depth_like[0]
    elif not depth_like:
        raise InputError(
            f"{source.path}: no aligned depth image (sensor_msgs/Image, 16UC1 or 32FC1); the bag has: "
            f"{_listing(source.topics.values())}"
        )
    else:
        raise InputError(
            f"{source.path}: several depth images, choose one with --depth-topic: "
            + "; ".join(f"{t.describe()} {encodings[t.name]}" for t in depth_like)
        )
    assert depth is not None

    if options.detections_topic is not None:
        perception = _pick(
            source, options.detections_topic, (DETECTION_2D_ARRAY,), "", "--detections-topic", True
        )
    elif options.image_topic is not None:
        perception = _pick(source, options.image_topic, (IMAGE, COMPRESSED_IMAGE), "", "--image-topic", True)
    else:
        detections = [t for t in source.topics.values() if t.msgtype == DETECTION_2D_ARRAY]
        compressed = [t for t in source.topics.values() if t.msgtype == COMPRESSED_IMAGE]
        colour = [t for t in colour_like if t.name != depth.name]
        if len(detections) == 1:
            perception = detections[0]
        elif detections:
            raise InputError(
                f"{source.path}: several detection topics, choose one with --detections-topic: "
                f"{_listing(detections)}"
            )
        elif len(colour) + len(compressed) == 1:
            perception = (colour + compressed)[0]
        elif not colour and not compressed:
            raise InputError(
                f"{source.path}: no colour image or vision_msgs/Detection2DArray topic; the bag has: "
                f"{_listing(source.topics.values())}"
            )
        else:
            listed = "; ".join(f"{t.describe()}" for t in colour + compressed)
            raise InputError(
                f"{source.path}: several colour image topics, choose one with --image-topic: {listed}"
            )
    assert perception is not None
    if perception.name == depth.name:
        raise InputError(f"{depth.name} is the depth image; the colour image must be another topic")

    camera_info = _pick(
        source, options.camera_info_topic, (CAMERA_INFO,), "camera info", "--camera-info-topic", False
    )
    if camera_info is None:
        raise InputError(
            f"{source.path}: no sensor_msgs/CameraInfo topic: the camera intrinsics are needed "
            f"(the bag has: {_listing(source.topics.values())})"
        )
    odom = _pick(source, options.odom_topic, (ODOMETRY,), "odometry", "--odom-topic", False)
    tf = source.topics.get("/tf") if source.topics.get("/tf", Topic("", "")).msgtype == TF_MESSAGE else None
    tf_static = (
        source.topics.get("/tf_static")
        if source.topics.get("/tf_static", Topic("", "")).msgtype == TF_MESSAGE
        else None
    )
    if odom is None and tf is None:
        raise InputError(f"{source.path}: no odometry: neither nav_msgs/Odometry nor /tf in the bag")
    scan = _pick(source, options.scan_topic, (LASER_SCAN,), "laser scan", "--scan-topic", False)
    return BagTopics(perception, depth, camera_info, odom, tf, tf_static, scan)


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
        total = sum(
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
        done = 0

        def tick() -> None:
            nonlocal done
            done += 1
            stats.messages += 1
            if progress is not None and done % 50 == 0:
                progress(done, total)

        # Pass 1: everything but the images.
        tree = TransformTree()
        camera_msg = None
        odom_samples: list[tuple[float, Pose2D]] = []
        odom_child: str | None = None
        tf_edges: list[tuple[float, str, str, Pose2D]] = []
        scans: list[Scan] = []
        clock: dict[str, list[float]] = {}
        first_pass = [
            t.name for t in (topics.camera_info, topics.odom, topics.tf, topics.tf_static, topics.scan) if t
        ]
        for name, bag_ns, msg in source.messages(first_pass):
            tick()
            if name == topics.camera_info.name:
                if camera_msg is None:
                    camera_msg = msg
                continue
            if topics.tf_static is not None and name == topics.tf_static.name:
                for tr in msg.transforms:
                    tree.add(checked_transform(name, tr))
                continue
            if topics.tf is not None and name == topics.tf.name:
                for tr in msg.transforms:
                    e = checked_transform(name, tr)
                    tf_edges.append(
                        (stamp_seconds(tr, bag_ns), e.parent, e.child, _planar(e.rotation, e.translation))
                    )
                continue
            t = stamp_seconds(msg, bag_ns)
            clock.setdefault(name, []).append(t)
            if topics.odom is not None and name == topics.odom.name:
                p, q = msg.pose.pose.position, msg.pose.pose.orientation
                finite(name, "an Odometry pose", p.x, p.y, q.x, q.y, q.z, q.w)
                odom_samples.append((t, Pose2D(float(p.x), float(p.y), quaternion_yaw(q.x, q.y, q.z, q.w))))
                odom_child = frame_name(msg.child_frame_id) or odom_child
            elif topics.scan is not None and name == topics.scan.name:
                finite(
                    name,
                    "a LaserScan's angles or range_max",
                    msg.angle_min,
                    msg.angle_increment,
                    msg.range_max,
                )
                ranges = np.asarray(msg.ranges, dtype=float)  # NaN, inf: no return (the sensor's way)
                ranges = np.where(np.isfinite(ranges) & (ranges >= float(msg.range_min)), ranges, math.nan)
                scans.append(
                    Scan(
                        t,
                        float(msg.angle_min),
                        float(msg.angle_increment),
                        float(msg.range_max),
                        tuple(ranges.tolist()),
                    )
                )
        for name, times in clock.items():
            _check_clock(name, times)
        if camera_msg is None:
            raise InputError(f"{topics.camera_info.name}: no CameraInfo message in the bag")
        camera = intrinsics(camera_msg, topics.camera_info.name)
        optical_frame = frame_name(camera_msg.header.frame_id)

        base = frame_name(options.base_frame) if options.base_frame else None
        if topics.odom is not None:
            if not odom_samples:
                raise InputError(f"{topics.odom.name}: no odometry message")
            base = base or odom_child or "base_link"
            if odom_child and odom_child != base:  # odometry of another frame: carry it to the base
                r, tr = tree.lookup(odom_child, base)
                offset = _planar(r, tr)
                odom_samples = [(t, p * offset) for t, p in odom_samples]
        else:
            children = sorted({c for _, parent, c, _ in tf_edges if parent == "odom"})
            if base is None:
                if len(children) != 1:
                    raise InputError(
                        "/tf: cannot tell the base frame (children of odom: "
                        f"{', '.join(children) or 'none'}); "
                        "use --base-frame"
                    )
                base = children[0]
            odom_samples = [(t, p) for t, parent, c, p in tf_edges if c == base and parent == "odom"]
            if not odom_samples:
                raise InputError(f"/tf: no odom -> {base} transform; use --base-frame or --odom-topic")
            _check_clock(f"/tf odom -> {base}", [t for t, _ in odom_samples])
        rotation, translation = tree.lookup(base, optical_frame)
        mount: CameraMount = mount_from_optical(rotation, translation)
        trajectory = _Trajectory.of(odom_samples)
        origin = Pose2D(float(trajectory.x[0]), float(trajectory.y[0]), float(trajectory.yaw[0])).inverse()

        records: list[Odom | Scan | Detections] = []  # each with a time stamp t
        for i in range(len(trajectory.t)):
            p = origin * Pose2D(float(trajectory.x[i]), float(trajectory.y[i]), float(trajectory.yaw[i]))
            records.append(Odom(float(trajectory.t[i]), p.x, p.y, float(wrap_angle(p.yaw))))
        stats.odom = len(trajectory.t)
        records.extend(scans)
        stats.scans = len(scans)

        # Pass 2: perception, each with the depth image nearest in time.
        perceiver = _Perceiver(topics.perception_kind, options, stats, topics.perception.name)
        depths: deque[tuple[float, Any]] = deque(maxlen=DEPTH_BUFFER)
        pending: deque[tuple[float, Any]] = deque()
        last_kept = -math.inf
        seen: dict[str, list[float]] = {topics.perception.name: [], topics.depth.name: []}

        def resolve(item_t: float, msg: Any) -> None:
            best = min(depths, key=lambda d: abs(d[0] - item_t), default=None)
            if best is None or abs(best[0] - item_t) > DEPTH_SYNC_S:
                stats.without_depth += 1
                return
            pose = trajectory.at(item_t)
            if pose is None:
                stats.outside_odometry += 1
                return
            depth = decode_depth(best[1])
            if depth.shape != (camera.height, camera.width):
                raise InputError(
                    f"{topics.depth.name}: depth image {depth.shape[1]}x{depth.shape[0]} is not aligned with "
                    f"the colour camera ({camera.width}x{camera.height})"
                )
            objects = perceiver.objects(msg, depth)
            local = origin * pose
            records.append(
                Detections(item_t, Pose2D(local.x, local.y, float(wrap_angle(local.yaw))), objects)
            )
            stats.images += 1
            stats.objects += len(objects)
            stats.objects_without_depth += sum(o.depth is None for o in objects)

        for name, bag_ns, msg in source.messages([topics.perception.name, topics.depth.name]):
            tick()
            t = stamp_seconds(msg, bag_ns)
            seen[name].append(t)
            if name == topics.depth.name:
                depths.append((t, msg))
            else:
                if options.rate is not None and t - last_kept < 1.0 / options.rate - 1e-9:
                    stats.skipped_rate += 1
                    continue
                last_kept = t
                pending.append((t, msg))
            latest = depths[-1][0] if depths else -math.inf
            while pending and latest >= pending[0][0]:
                resolve(*pending.popleft())
            while pending and len(depths) == depths.maxlen and depths[0][0] > pending[0][0] + DEPTH_SYNC_S:
                resolve(*pending.popleft())
        while pending:
            resolve(*pending.popleft())
        for name, times in seen.items():
            _check_clock(name, times)
        if progress is not None:
            progress(total, total)

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
    records.sort(key=lambda r: r.t)
    meta = Meta(
        camera=camera,
        camera_pose=mount,
        depth_window=options.depth_window,
        source=f"bim-init bag2log {path.name} ({topics.perception.name}, base frame {base})",
    )
    stats.seconds = time.perf_counter() - started
    return [meta, *records], stats
