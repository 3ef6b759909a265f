"""Bags out: any messages to a ROS 1 ``.bag``, a ROS 2 sqlite3 folder or a ROS 2 ``.mcap`` file, and
a simulated session (its ``session.jsonl``, ``summary.json`` and site) as a ROS 2 MCAP bag.

The session bag holds what a real robot would have recorded plus the result: the detections
(``vision_msgs/Detection2DArray``, Humble layout), an aligned 32FC1 depth image (each box centre's
window at the log's depth, so ``bag2log`` gives back the log's depths), ``camera_info``, ``/scan``,
``/odom``, ``/tf`` (odom -> base_link, and map -> odom from the claim on: the result's
transform), ``/tf_static`` (base_link -> camera_link -> camera_color_optical_frame), the BIM map as
``nav_msgs/OccupancyGrid`` on ``/map``, ``/initialpose``, the hypotheses and the states. A live
session's bag is on the robot's clock (``summary.json``'s ``clock.origin_stamp``) and its
``/initialpose`` is the pose that was sent (``published``). Every ROS 2 topic carries its QoS
profile: ``/tf_static`` and ``/map`` transient local (latched under ``ros2 bag play``).
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import load_site
from bimtools.site.records import OccupancyGrid
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import DetectionLog, Detections, HypothesesRecord, Odom, Scan, State, read_log
from initcli.ros.msgdefs import from_dict, ros1_typestore, ros2_typestore
from initcli.ros.nav2 import (
    hypothesis_poses,
    initial_pose_message,
    pose_array_message,
    pose_dict,
    read_summary,
    session_initial_pose,
    stamp_dict,
    state_message,
)
from initcli.ros.records import (
    CAMERA_INFO,
    DETECTION_2D_ARRAY,
    HYPOTHESES_TOPIC,
    IMAGE,
    INITIALPOSE_TOPIC,
    LASER_SCAN,
    MAP_TOPIC,
    OCCUPANCY_GRID,
    ODOMETRY,
    POSE_ARRAY,
    POSE_WITH_COVARIANCE_STAMPED,
    STATE_TOPIC,
    STRING,
    TF_MESSAGE,
    InitialPose,
)
from initcli.ros.tf import matrix_quaternion, yaw_quaternion

__all__ = [
    "BASE_FRAME",
    "BagMessage",
    "BagWriter",
    "CAMERA_FRAME",
    "CAMERA_INFO_TOPIC",
    "DEPTH_TOPIC",
    "DETECTIONS_TOPIC",
    "OPTICAL_FRAME",
    "camera_info",
    "camera_tf",
    "colour_image",
    "depth_image",
    "detection_array",
    "header",
    "laser_scan",
    "ns",
    "occupancy_grid",
    "odometry",
    "record_session",
    "session_messages",
    "transform_stamped",
    "write_bag",
]

BASE_FRAME = "base_link"
CAMERA_FRAME = "camera_link"
OPTICAL_FRAME = "camera_color_optical_frame"
DETECTIONS_TOPIC = "/camera/detections"
DEPTH_TOPIC = "/camera/aligned_depth_to_color/image_raw"
CAMERA_INFO_TOPIC = "/camera/color/camera_info"


@dataclass(frozen=True)
class BagMessage:
    topic: str
    msgtype: str
    t: float  # s: bag time (and, for messages with a header, its stamp)
    value: dict[str, Any]


def ns(t: float) -> int:
    return max(0, int(round(t * 1e9)))


def _qos(durability: str) -> Any:
    """A reliable keep-last-10 QoS profile (depth 1 for ``transient_local``), as rosbag2 stores it."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    latched = durability == "transient_local"
    never = QosTime(0, 0)  # rosbag2 writes "unset" (infinite) deadlines and lifespans as 0
    return Qos(
        QosHistory.KEEP_LAST,
        1 if latched else 10,
        QosReliability.RELIABLE,
        QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE,
        never,
        never,
        QosLiveliness.AUTOMATIC,
        never,
        False,
    )


LATCHED_TOPICS = ("/tf_static", MAP_TOPIC)  # transient local: a late subscriber still gets them


class BagWriter:
    """Write :class:`BagMessage` dicts: ``.bag`` -> ROS 1, ``.mcap`` -> one ROS 2 MCAP file, otherwise a
    ROS 2 sqlite3 bag folder. Written beside the target and moved there when complete."""

    def __init__(self, path: Path | str, vision_layout: str = "humble") -> None:
        self.path = Path(path)
        self.ros1 = self.path.suffix == ".bag"
        self.mcap = self.path.suffix == ".mcap"
        self.store = ros1_typestore(vision_layout) if self.ros1 else ros2_typestore(vision_layout)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", dir=self.path.parent))
        inner = self._tmp / ("bag.bag" if self.ros1 else "bag")
        if self.ros1:
            from rosbags.rosbag1 import Writer as Writer1

            self.writer: Any = Writer1(inner)
        else:
            from rosbags.rosbag2 import StoragePlugin, Writer
            from rosbags.rosbag2.enums import CompressionFormat, CompressionMode

            plugin = StoragePlugin.MCAP if self.mcap else StoragePlugin.SQLITE3
            self.writer = Writer(inner, version=9, storage_plugin=plugin)
            if self.mcap:
                self.writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self._inner = inner
        self.writer.open()
        self.connections: dict[str, Any] = {}

    def write(self, message: BagMessage) -> None:
        conn = self.connections.get(message.topic)
        if conn is None:
            if self.ros1:
                conn = self.writer.add_connection(
                    message.topic,
                    message.msgtype,
                    typestore=self.store,
                    latching=1 if message.topic in LATCHED_TOPICS else None,
                )
            else:
                durability = "transient_local" if message.topic in LATCHED_TOPICS else "volatile"
                conn = self.writer.add_connection(
                    message.topic,
                    message.msgtype,
                    typestore=self.store,
                    offered_qos_profiles=[_qos(durability)],
                )
            self.connections[message.topic] = conn
        msg = from_dict(self.store, message.msgtype, message.value)
        data = (
            self.store.serialize_ros1(msg, message.msgtype)
            if self.ros1
            else self.store.serialize_cdr(msg, message.msgtype)
        )
        self.writer.write(conn, ns(message.t), data)

    def write_all(self, messages: Iterable[BagMessage]) -> None:
        for m in messages:
            self.write(m)

    def close(self) -> None:
        self.writer.close()
        if self.ros1:
            source = self._inner
        elif self.mcap:
            source = next(self._inner.glob("*.mcap"))
        else:
            source = self._inner
        if self.path.is_dir():
            shutil.rmtree(self.path)
        os.replace(source, self.path)
        shutil.rmtree(self._tmp, ignore_errors=True)

    def abort(self) -> None:
        try:
            self.writer.close()
        except Exception:  # noqa: BLE001 - the bag is discarded anyway
            pass
        shutil.rmtree(self._tmp, ignore_errors=True)

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, kind: object, *exc: object) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()


def write_bag(path: Path | str, messages: Iterable[BagMessage], vision_layout: str = "humble") -> Path:
    with BagWriter(path, vision_layout) as writer:
        writer.write_all(messages)
    return Path(path)


# --- message dicts ---------------------------------------------------------------------------------


def header(t: float, frame_id: str) -> dict[str, Any]:
    return {"stamp": stamp_dict(t), "frame_id": frame_id}


def transform_stamped(
    t: float, parent: str, child: str, translation: Iterable[float], quaternion: tuple[float, ...]
) -> dict[str, Any]:
    x, y, z = (float(v) for v in translation)
    qx, qy, qz, qw = quaternion
    return {
        "header": header(t, parent),
        "child_frame_id": child,
        "transform": {
            "translation": {"x": x, "y": y, "z": z},
            "rotation": {"x": qx, "y": qy, "z": qz, "w": qw},
        },
    }


def camera_tf(t: float, mount: CameraMount, base: str = BASE_FRAME) -> list[dict[str, Any]]:
    """base -> camera_link (the camera body: the log's camera_pose) -> optical frame (REP 103 axes)."""
    from initcli.core.geometry.projection import R_BODY_OPTICAL

    return [
        transform_stamped(t, base, CAMERA_FRAME, mount.translation, matrix_quaternion(mount.rotation())),
        transform_stamped(t, CAMERA_FRAME, OPTICAL_FRAME, (0.0, 0.0, 0.0), matrix_quaternion(R_BODY_OPTICAL)),
    ]


def camera_info(t: float, cam: CameraIntrinsics, frame: str = OPTICAL_FRAME) -> dict[str, Any]:
    return {
        "header": header(t, frame),
        "height": cam.height,
        "width": cam.width,
        "distortion_model": "plumb_bob",
        "d": [0.0] * 5,
        "k": [cam.fx, 0.0, cam.cx, 0.0, cam.fy, cam.cy, 0.0, 0.0, 1.0],
        "r": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        "p": [cam.fx, 0.0, cam.cx, 0.0, 0.0, cam.fy, cam.cy, 0.0, 0.0, 0.0, 1.0, 0.0],
    }


def depth_image(
    t: float, depth: np.ndarray, frame: str = OPTICAL_FRAME, encoding: str = "32FC1"
) -> dict[str, Any]:
    """A depth image in metres as 32FC1, or 16UC1 millimetres."""
    if encoding == "16UC1":
        arr = np.round(np.nan_to_num(depth, nan=0.0) * 1000.0).clip(0, 65535).astype("<u2")
    else:
        arr = depth.astype("<f4")
    h, w = arr.shape
    return {
        "header": header(t, frame),
        "height": h,
        "width": w,
        "encoding": encoding,
        "is_bigendian": 0,
        "step": w * arr.itemsize,
        "data": np.ascontiguousarray(arr).view(np.uint8).reshape(-1),
    }


def colour_image(t: float, bgr: np.ndarray, frame: str = OPTICAL_FRAME) -> dict[str, Any]:
    h, w = bgr.shape[:2]
    return {
        "header": header(t, frame),
        "height": h,
        "width": w,
        "encoding": "bgr8",
        "is_bigendian": 0,
        "step": w * 3,
        "data": np.ascontiguousarray(bgr, dtype=np.uint8).reshape(-1),
    }


def detection_array(
    t: float,
    objects: Iterable[tuple[str, float, tuple[float, float, float, float]]],
    frame: str = OPTICAL_FRAME,
) -> dict[str, Any]:
    """``vision_msgs/Detection2DArray`` (Humble layout) of (class, score, [u1, v1, u2, v2]) boxes."""
    dets = []
    for cls, score, (u1, v1, u2, v2) in objects:
        dets.append(
            {
                "header": header(t, frame),
                "results": [{"hypothesis": {"class_id": cls, "score": score}}],
                "bbox": {
                    "center": {"position": {"x": (u1 + u2) / 2.0, "y": (v1 + v2) / 2.0}},
                    "size_x": u2 - u1,
                    "size_y": v2 - v1,
                },
            }
        )
    return {"header": header(t, frame), "detections": dets}


def odometry(t: float, pose: Pose2D, frame: str = "odom", child: str = BASE_FRAME) -> dict[str, Any]:
    return {
        "header": header(t, frame),
        "child_frame_id": child,
        "pose": {"pose": pose_dict(pose.x, pose.y, pose.yaw)},
    }


def laser_scan(t: float, scan: Scan, frame: str = BASE_FRAME) -> dict[str, Any]:
    ranges = np.array([r if math.isfinite(r) else math.inf for r in scan.ranges], dtype=np.float32)
    return {
        "header": header(t, frame),
        "angle_min": scan.angle_min,
        "angle_max": scan.angle_min + scan.angle_increment * max(len(ranges) - 1, 0),
        "angle_increment": scan.angle_increment,
        "range_min": 0.05,
        "range_max": scan.range_max,
        "ranges": ranges,
    }


def occupancy_grid(t: float, grid: OccupancyGrid, frame: str = "map") -> dict[str, Any]:
    """The site's PGM-style grid (0 occupied .. 254 free, 205 unknown) as nav_msgs/OccupancyGrid."""
    cells = np.asarray(grid.cells, dtype=float)
    p = (255.0 - cells) / 255.0 if not grid.negate else cells / 255.0  # map_server's occupancy
    data = np.where(p > grid.occupied_thresh, 100, np.where(p < grid.free_thresh, 0, -1)).astype(np.int8)
    data = data[::-1]  # row 0 of nav_msgs is the bottom row (origin); cells[0] is the top row
    rows, cols = data.shape
    ox, oy, oyaw = grid.origin
    return {
        "header": header(t, frame),
        "info": {
            "map_load_time": stamp_dict(t),
            "resolution": grid.resolution,
            "width": cols,
            "height": rows,
            "origin": pose_dict(ox, oy, oyaw),
        },
        "data": data.reshape(-1),
    }


def _object_depths(cam: CameraIntrinsics, detections: Detections, window: int) -> np.ndarray:
    """An aligned depth image that holds each object's depth in its (2n+1)^2 window (0 elsewhere)."""
    depth = np.zeros((cam.height, cam.width), np.float32)
    for o in detections.objects:
        if o.depth is None:
            continue
        u, v = (o.bbox[0] + o.bbox[2]) / 2.0, (o.bbox[1] + o.bbox[3]) / 2.0
        cu, cv = int(math.floor(u)), int(math.floor(v))
        if 0 <= cu < cam.width and 0 <= cv < cam.height:
            depth[max(0, cv - window) : cv + window + 1, max(0, cu - window) : cu + window + 1] = o.depth
    return depth


def _claim_time(log: DetectionLog, summary: dict[str, Any]) -> float:
    """Session time of the claim: the live summary's ``claim`` stamp, else the first state after
    the unique match (``fine``, or ``done`` without fine tuning), else the session's end."""
    claim = summary.get("claim")
    origin = (summary.get("clock") or {}).get("origin_stamp")
    if isinstance(claim, dict) and origin is not None:
        return float(claim["stamp"]) - float(origin)
    for rec in log.records:
        if isinstance(rec, State) and rec.t is not None and rec.data.get("state") in ("fine", "done"):
            return float(rec.t)
    return float(summary.get("duration_s", 0.0))


def _sent_pose(summary: dict[str, Any], log: DetectionLog, origin: float) -> InitialPose:
    """What went to ``/initialpose`` (a live session's ``published`` pose), else the session's pose
    at its newest odometry, on the robot's clock."""
    pose = session_initial_pose(summary, log.path)
    if isinstance(summary.get("published"), dict):
        return pose
    return InitialPose(pose.stamp + origin, pose.x, pose.y, pose.yaw, pose.covariance)


def _tf(t: float, parent: str, child: str, pose: Pose2D) -> dict[str, Any]:
    return {
        "transforms": [transform_stamped(t, parent, child, (pose.x, pose.y, 0.0), yaw_quaternion(pose.yaw))]
    }


def session_messages(
    log: DetectionLog, summary: dict[str, Any] | None, grid: OccupancyGrid | None
) -> Iterator[BagMessage]:
    """The messages of a session's bag, from its log (and result and map when given); a live
    session's on the robot's clock."""
    meta = log.meta
    window = meta.depth_window if meta.depth_window is not None else 2
    origin = float(((summary or {}).get("clock") or {}).get("origin_stamp") or 0.0)
    first = log.records[0].t if log.records and log.records[0].t is not None else 0.0  # type: ignore[union-attr]
    t0 = origin + first
    yield BagMessage("/tf_static", TF_MESSAGE, t0, {"transforms": camera_tf(t0, meta.camera_pose)})
    if grid is not None:
        yield BagMessage(MAP_TOPIC, OCCUPANCY_GRID, t0, occupancy_grid(t0, grid))
    success = summary is not None and bool(summary.get("success"))
    map_from_odom: Pose2D | None = None
    claim_t = math.inf
    if success and summary is not None and log.odom:
        p = summary["pose"]
        final = Pose2D(float(p["x"]), float(p["y"]), math.radians(float(p["yaw_deg"])))
        map_from_odom = final * log.odom[-1].pose.inverse()  # the session ends on its claim
        claim_t = _claim_time(log, summary)
    for rec in log.records:
        t = origin + (getattr(rec, "t", None) or 0.0)
        if isinstance(rec, Odom):
            pose = rec.pose
            yield BagMessage("/odom", ODOMETRY, t, odometry(t, pose))
            yield BagMessage("/tf", TF_MESSAGE, t, _tf(t, "odom", BASE_FRAME, pose))
            if map_from_odom is not None and rec.t >= claim_t - 1e-6:
                yield BagMessage("/tf", TF_MESSAGE, t, _tf(t, "map", "odom", map_from_odom))
        elif isinstance(rec, Detections):
            objs = [(o.cls, o.score, o.bbox) for o in rec.objects]
            yield BagMessage(CAMERA_INFO_TOPIC, CAMERA_INFO, t, camera_info(t, meta.camera))
            yield BagMessage(DETECTIONS_TOPIC, DETECTION_2D_ARRAY, t, detection_array(t, objs))
            yield BagMessage(DEPTH_TOPIC, IMAGE, t, depth_image(t, _object_depths(meta.camera, rec, window)))
        elif isinstance(rec, Scan):
            yield BagMessage("/scan", LASER_SCAN, t, laser_scan(t, rec))
        elif isinstance(rec, State) and rec.t is not None:
            yield BagMessage(STATE_TOPIC, STRING, t, state_message(str(rec.data.get("state", ""))))
        elif isinstance(rec, HypothesesRecord) and rec.t is not None:
            yield BagMessage(HYPOTHESES_TOPIC, POSE_ARRAY, t, pose_array_message(t, hypothesis_poses(rec)))
    if success and summary is not None:
        sent = _sent_pose(summary, log, origin)
        yield BagMessage(
            INITIALPOSE_TOPIC, POSE_WITH_COVARIANCE_STAMPED, sent.stamp, initial_pose_message(sent)
        )


def record_session(run_dir: Path, site_path: Path | None, bag: Path) -> Path:
    """``bim-init run --record``: the run folder's session as a ROS 2 MCAP bag."""
    run_dir = Path(run_dir)
    log = read_log(run_dir / "session.jsonl")
    summary = read_summary(run_dir / "summary.json") if (run_dir / "summary.json").exists() else None
    grid = None
    site_dir = run_dir / "site" if (run_dir / "site").exists() else site_path
    if site_dir is not None and Path(site_dir).is_dir():
        site = load_site(Path(site_dir))
        storey = (summary or {}).get("storey")
        model = site.storeys.get(storey) if storey else None
        model = model or next((s for s in site.storeys.values() if s.grid is not None), None)
        grid = model.grid if model is not None else None
    if bag.suffix != ".mcap":
        raise InputError(f"--record {bag}: expected a .mcap file name")
    return write_bag(bag, session_messages(log, summary, grid))
