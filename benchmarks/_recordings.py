"""Synthetic robot recordings written with rosbags' writers (ROS 1, ROS 2 sqlite3, ROS 2 MCAP).

Shared by ``benchmarks/bench_bag2log.py`` and the tests of the ROS readers, ``bim-init bag2log``
and the rosbridge driver (``tests/initcli/ros``, ``tests/initcli/cli``), which import it as
``benchmarks._recordings``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, box_for_point, odom_to_pixel
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import Scan
from initcli.ros.bag_writer import (
    BagMessage,
    camera_info,
    camera_tf,
    colour_image,
    depth_image,
    header,
    laser_scan,
    odometry,
    transform_stamped,
    write_bag,
)
from initcli.ros.records import (
    CAMERA_INFO,
    COMPRESSED_IMAGE,
    DETECTION_2D_ARRAY,
    IMAGE,
    LASER_SCAN,
    ODOMETRY,
    TF_MESSAGE,
)
from initcli.ros.tf import yaw_quaternion

CAMERA = CameraIntrinsics(fx=320.0, fy=320.0, cx=320.0, cy=240.0, width=640, height=480)
MOUNT = CameraMount(x=0.25, y=-0.05, z=0.9, roll=0.0, pitch=math.radians(8.0), yaw=math.radians(4.0))
# Feature points in the robot's start frame (what bag2log's odom frame is).
POINTS = {"door": (4.0, 1.2, 1.0), "lift": (6.5, -1.0, 1.1), "stairs": (9.0, 0.8, 0.9)}
START = Pose2D(3.0, -2.0, math.radians(30.0))  # the odometry's own origin is elsewhere


@dataclass
class Recording:
    messages: list[BagMessage]
    image_times: list[float]
    truth_local: dict[float, Pose2D] = field(default_factory=dict)  # image t -> pose in the log frame


def local_pose(t: float) -> Pose2D:
    """The robot's path in its start frame: forward at 0.4 m/s, turning slowly."""
    return Pose2D(0.4 * t, 0.05 * t * t, 0.04 * t)


def detections_value(t: float, boxes: list[tuple[str, float, tuple]], layout: str, numeric: bool) -> dict:
    """A Detection2DArray dict in a vision_msgs layout (:data:`initcli.ros.msgdefs.VISION_MSGS_LAYOUTS`;
    Noetic's ``int64`` ids are numeric whatever ``numeric`` says)."""
    names = {"door": "0", "lift": "1", "stairs": "2"}
    dets = []
    for cls, score, (u1, v1, u2, v2) in boxes:
        cid = names[cls] if numeric or layout == "noetic" else cls
        cu, cv = (u1 + u2) / 2, (v1 + v2) / 2
        if layout in ("humble", "galactic"):
            result: dict = {"hypothesis": {"class_id": cid, "score": score}}
        else:
            result = {"id": int(cid) if layout == "noetic" else cid, "score": score}
        if layout == "humble":
            centre: dict = {"position": {"x": cu, "y": cv}, "theta": 0.0}
        else:
            centre = {"x": cu, "y": cv, "theta": 0.0}
        det: dict = {
            "header": header(t, "cam_optical"),
            "results": [result],
            "bbox": {"center": centre, "size_x": u2 - u1, "size_y": v2 - v1},
        }
        if layout == "foxy":
            det |= {"is_tracking": True, "tracking_id": f"track-{cls}"}
        dets.append(det)
    return {"header": header(t, "cam_optical"), "detections": dets}


def make_recording(
    *,
    perception: str = "detections",  # detections | image | compressed
    layout: str = "humble",
    numeric: bool = False,
    depth_encoding: str = "32FC1",
    odom_source: str = "odometry",  # odometry | tf
    t0: float = 1_700_000_000.0,
    duration: float = 6.0,
    image_rate: float = 5.0,
    with_depth: bool = True,
    with_camera_info: bool = True,
    image_offset: float = 0.013,  # images fall between odometry stamps
) -> Recording:
    msgs: list[BagMessage] = []
    tf_static = camera_tf(t0, MOUNT, base="base_link")
    tf_static[1]["child_frame_id"] = "cam_optical"
    msgs.append(BagMessage("/tf_static", TF_MESSAGE, t0, {"transforms": tf_static}))
    for k in range(int(duration * 20) + 1):  # odometry at 20 Hz
        t = k / 20.0
        pose = START * local_pose(t)
        if odom_source == "odometry":
            msgs.append(BagMessage("/odom", ODOMETRY, t0 + t, odometry(t0 + t, pose)))
        else:
            tr = transform_stamped(
                t0 + t, "odom", "base_link", (pose.x, pose.y, 0.0), yaw_quaternion(pose.yaw)
            )
            msgs.append(BagMessage("/tf", TF_MESSAGE, t0 + t, {"transforms": [tr]}))
        if k % 4 == 0:
            scan = Scan(t0 + t, -math.pi, math.radians(1.0), 20.0, tuple([3.0] * 180 + [math.nan] * 180))
            msgs.append(BagMessage("/scan", LASER_SCAN, t0 + t, laser_scan(t0 + t, scan)))
    rec = Recording(msgs, [])
    n_images = int(duration * image_rate)
    for i in range(n_images):
        t = image_offset + i / image_rate
        ts = t0 + t
        robot = local_pose(t)
        depth = np.zeros((CAMERA.height, CAMERA.width), np.float32)
        boxes = []
        for cls, p in POINTS.items():
            u, v, d = odom_to_pixel(np.array([p]), CAMERA, MOUNT, robot)
            u, v, d = float(u[0]), float(v[0]), float(d[0])
            if d <= 0.3 or not (5 <= u < CAMERA.width - 5 and 5 <= v < CAMERA.height - 5):
                continue
            boxes.append((cls, 0.9, box_for_point(u, v, d, 1.0, 2.0, CAMERA)))
            cu, cv = int(math.floor(u)), int(math.floor(v))
            depth[cv - 3 : cv + 4, cu - 3 : cu + 4] = d
        rec.image_times.append(ts)
        rec.truth_local[ts] = robot
        if with_camera_info:
            msgs.append(
                BagMessage(
                    "/camera/color/camera_info", CAMERA_INFO, ts, camera_info(ts, CAMERA, "cam_optical")
                )
            )
        if with_depth:
            msgs.append(
                BagMessage(
                    "/camera/depth/image", IMAGE, ts, depth_image(ts, depth, "cam_optical", depth_encoding)
                )
            )
        if perception == "detections":
            msgs.append(
                BagMessage(
                    "/detections", DETECTION_2D_ARRAY, ts, detections_value(ts, boxes, layout, numeric)
                )
            )
        else:
            bgr = door_image(i)
            if perception == "image":
                msgs.append(
                    BagMessage("/camera/color/image_raw", IMAGE, ts, colour_image(ts, bgr, "cam_optical"))
                )
            else:
                ok, png = cv2.imencode(".png", bgr)
                assert ok
                value = {
                    "header": header(ts, "cam_optical"),
                    "format": "png",
                    "data": np.frombuffer(png.tobytes(), np.uint8),
                }
                msgs.append(BagMessage("/camera/color/image_raw/compressed", COMPRESSED_IMAGE, ts, value))
    msgs.sort(key=lambda m: m.t)
    return rec


def door_image(i: int) -> np.ndarray:
    """A 640x480 picture with a dark door-like slab on a light wall (varies with i)."""
    img = np.full((CAMERA.height, CAMERA.width, 3), 200, np.uint8)
    x = 200 + 10 * i
    img[80:470, x : x + 140] = (60, 70, 90)
    img[270:290, x + 110 : x + 125] = (20, 20, 20)
    return img


def write(tmp_path: Path, recording: Recording, fmt: str, layout: str = "humble", name: str = "rec") -> Path:
    suffix = {"ros1": ".bag", "mcap": ".mcap", "sqlite3": ""}[fmt]
    return write_bag(tmp_path / f"{name}{suffix}", recording.messages, vision_layout=layout)
