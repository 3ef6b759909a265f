"""The camera of a live robot, as ``bag2log`` takes it from a bag: the intrinsics from
``CameraInfo``, the camera mount from ``/tf_static`` (base frame -> the CameraInfo's optical
frame). The site config's ``camera:`` values are the fallback when the robot sends neither in
``robot.rosbridge.camera_wait`` seconds; where both exist and disagree, a warning says so (the
robot's values are used).

A robot without a camera (``robot.rosbridge.camera: absent``, or ``auto`` where rosapi lists no
publisher of the detections topic; without rosapi the camera is taken as present):
:class:`LiveCamera` says ``absent`` (the placeholder camera of a lidar-only log, one warning line
when detected), and the session runs on the lidar alone.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, mount_from_optical
from initcli.io.log_records import NO_CAMERA, NO_MOUNT
from initcli.ros.messages import intrinsics
from initcli.ros.records import CAMERA_INFO, TF_MESSAGE
from initcli.ros.rosbridge import RosbridgeLink
from initcli.ros.rosbridge_driver import StaticTransforms, _ns
from initcli.ros.tf import frame_name

__all__ = ["LiveCamera", "MOUNT_TOLERANCE_DEG", "MOUNT_TOLERANCE_M", "live_camera"]

INTRINSICS_TOLERANCE = 0.01  # relative: fx, fy, cx, cy
MOUNT_TOLERANCE_M = 0.02
MOUNT_TOLERANCE_DEG = 1.0
ROSAPI_TIMEOUT_S = 2.0  # s: rosapi asked whether the detections topic has a publisher


@dataclass
class LiveCamera:
    camera: CameraIntrinsics
    mount: CameraMount
    intrinsics_from: str  # "CameraInfo <topic>" or "camera: (site config)"
    mount_from: str  # "/tf_static <base> -> <frame>" or "camera.pose (site config)"
    warnings: list[str] = field(default_factory=list)
    absent: bool = False  # no camera: the session runs on the lidar alone
    absent_because: str = ""

    def record(self) -> dict[str, Any]:
        out: dict[str, Any] = {"intrinsics": self.intrinsics_from, "mount": self.mount_from}
        out |= {"absent": self.absent, "warnings": list(self.warnings)}
        if self.absent:
            out["absent_because"] = self.absent_because
        return out


def _intrinsics_differ(a: CameraIntrinsics, b: CameraIntrinsics) -> bool:
    if (a.width, a.height) != (b.width, b.height):
        return True
    return any(
        abs(x - y) > INTRINSICS_TOLERANCE * max(abs(y), 1.0)
        for x, y in ((a.fx, b.fx), (a.fy, b.fy), (a.cx, b.cx), (a.cy, b.cy))
    )


def _mount_differs(a: CameraMount, b: CameraMount) -> bool:
    if float(np.linalg.norm(a.translation - b.translation)) > MOUNT_TOLERANCE_M:
        return True
    r = a.rotation().T @ b.rotation()
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(r)) - 1.0) / 2.0))))
    return angle > MOUNT_TOLERANCE_DEG


def _camera_text(c: CameraIntrinsics) -> str:
    return f"fx {c.fx:g} fy {c.fy:g} cx {c.cx:g} cy {c.cy:g} {c.width}x{c.height}"


def _mount_text(m: CameraMount) -> str:
    return (
        f"x {m.x:.3f} y {m.y:.3f} z {m.z:.3f} m, roll {math.degrees(m.roll):.1f} pitch "
        f"{math.degrees(m.pitch):.1f} yaw {math.degrees(m.yaw):.1f} deg"
    )


def _absent(why: str) -> LiveCamera:
    none = "none: the camera is absent"
    return LiveCamera(NO_CAMERA, NO_MOUNT, none, none, absent=True, absent_because=why)


def _camera_presence(link: RosbridgeLink, topics: Any) -> bool | None:
    """``robot.rosbridge.camera``: False for absent; True for present, or auto where rosapi lists a
    publisher of the detections topic; None: auto and nobody can tell (no rosapi)."""
    if topics.camera == "absent":
        return False
    if topics.camera == "present":
        return True
    return link.publisher_up(topics.detections_topic, ROSAPI_TIMEOUT_S)


def _wait_camera(
    link: RosbridgeLink, topics: Any, static: StaticTransforms, base_frame: str
) -> tuple[Any, tuple[np.ndarray, np.ndarray] | None]:
    """Up to ``topics.camera_wait`` s for CameraInfo and the /tf_static chain from ``base_frame``
    to its frame: (CameraInfo or None, mount or None)."""
    lock = threading.Lock()
    info: list[Any] = []
    got = threading.Event()

    def on_info(msg: dict[str, Any]) -> None:
        with lock:
            if not info:
                info.append(_ns(msg))
        got.set()

    link.subscribe(topics.camera_info_topic, CAMERA_INFO, on_info)
    deadline = time.monotonic() + float(topics.camera_wait)
    camera_msg: Any = None
    mount: tuple[np.ndarray, np.ndarray] | None = None
    while time.monotonic() < deadline:
        got.wait(max(0.0, min(0.02, deadline - time.monotonic())))
        got.clear()
        with lock:
            camera_msg = info[0] if info else None
        if camera_msg is not None:
            try:
                mount = static.lookup(base_frame, frame_name(camera_msg.header.frame_id))
            except AttributeError:
                mount = None
            if mount is not None:
                break
    return camera_msg, mount


def live_camera(
    link: RosbridgeLink,
    topics: Any,  # initcli.config.RosbridgeSection
    fallback_camera: CameraIntrinsics,
    fallback_mount: CameraMount,
    base_frame: str,
    static: StaticTransforms | None = None,
) -> LiveCamera:
    """Whether the robot has a camera (``robot.rosbridge.camera``; auto: rosapi's publishers of the
    detections topic; without rosapi, present); where it has one, wait
    up to ``topics.camera_wait`` s for CameraInfo and the ``/tf_static`` chain from ``base_frame``
    to its frame: the camera to use and where each part came from. ``static``: the driver's
    ``/tf_static`` (None: subscribed here)."""
    present = _camera_presence(link, topics)
    if present is False:
        if topics.camera == "absent":
            return _absent("robot.rosbridge.camera: absent")
        out = _absent(f"rosapi lists no publisher of {topics.detections_topic}")
        out.warnings.append(
            f"rosapi lists no publisher of {topics.detections_topic}: no camera, the session runs on the "
            "lidar alone (robot.rosbridge.camera: present to wait for one)"
        )
        return out
    if static is None:
        static = StaticTransforms(topics.tf_static_topic)
        link.subscribe(topics.tf_static_topic, TF_MESSAGE, static.on_message)
    # auto without rosapi: nobody can tell, so the camera is taken as present (the site config's
    # camera: after camera_wait s without CameraInfo); a camera that then sees nothing leaves the
    # session to the lidar all the same
    camera_msg, mount = _wait_camera(link, topics, static, base_frame)
    out = LiveCamera(fallback_camera, fallback_mount, "camera: (site config)", "camera.pose (site config)")
    if camera_msg is None:
        out.warnings.append(
            f"no CameraInfo on {topics.camera_info_topic} in {topics.camera_wait:g} s: the intrinsics "
            "of the site config's camera: are used"
        )
    else:
        live = intrinsics(camera_msg, topics.camera_info_topic)
        if _intrinsics_differ(live, fallback_camera):
            out.warnings.append(
                f"{topics.camera_info_topic}: {_camera_text(live)} differ from the site config's camera: "
                f"({_camera_text(fallback_camera)}); the robot's are used"
            )
        out.camera, out.intrinsics_from = live, f"CameraInfo {topics.camera_info_topic}"
    if mount is None:
        frame = frame_name(camera_msg.header.frame_id) if camera_msg is not None else "the camera frame"
        out.warnings.append(
            f"no {topics.tf_static_topic} chain {base_frame} -> {frame} in {topics.camera_wait:g} s: the "
            "site config's camera.pose is used"
        )
    else:
        live_mount = mount_from_optical(*mount)
        if _mount_differs(live_mount, fallback_mount):
            out.warnings.append(
                f"{topics.tf_static_topic}: the camera mount ({_mount_text(live_mount)}) differs from the "
                f"site config's camera.pose ({_mount_text(fallback_mount)}); the robot's is used"
            )
        frame = frame_name(camera_msg.header.frame_id)
        out.mount, out.mount_from = live_mount, f"{topics.tf_static_topic} {base_frame} -> {frame}"
    return out
