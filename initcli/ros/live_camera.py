"""The camera of a live robot, as ``bag2log`` takes it from a bag: the intrinsics from
``CameraInfo``, the camera mount from ``/tf_static`` (base frame -> the CameraInfo's optical
frame). The site config's ``camera:`` values are the fallback when the robot sends neither in
``robot.rosbridge.camera_wait`` seconds; where both exist and disagree, a warning says so (the
robot's values are used).
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bimkit.errors import InputError
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, mount_from_optical
from initcli.ros.messages import checked_transform, intrinsics
from initcli.ros.records import CAMERA_INFO, TF_MESSAGE
from initcli.ros.rosbridge import RosbridgeLink
from initcli.ros.tf import TransformTree, frame_name

__all__ = ["LiveCamera", "MOUNT_TOLERANCE_DEG", "MOUNT_TOLERANCE_M", "live_camera"]

INTRINSICS_TOLERANCE = 0.01  # relative: fx, fy, cx, cy
MOUNT_TOLERANCE_M = 0.02
MOUNT_TOLERANCE_DEG = 1.0


@dataclass
class LiveCamera:
    camera: CameraIntrinsics
    mount: CameraMount
    intrinsics_from: str  # "CameraInfo <topic>" or "camera: (site config)"
    mount_from: str  # "/tf_static <base> -> <frame>" or "camera.pose (site config)"
    warnings: list[str] = field(default_factory=list)

    def record(self) -> dict[str, Any]:
        return {"intrinsics": self.intrinsics_from, "mount": self.mount_from, "warnings": list(self.warnings)}


def _ns(value: Any) -> Any:
    from initcli.ros.rosbridge_driver import _ns as ns

    return ns(value)


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


def live_camera(
    link: RosbridgeLink,
    topics: Any,  # initcli.config.RosbridgeSection
    fallback_camera: CameraIntrinsics,
    fallback_mount: CameraMount,
    base_frame: str,
) -> LiveCamera:
    """Wait up to ``topics.camera_wait`` s for CameraInfo and the ``/tf_static`` chain from
    ``base_frame`` to its frame; the camera to use and where each part came from."""
    lock = threading.Lock()
    info: list[Any] = []
    tree = TransformTree()
    got = threading.Event()

    def on_info(msg: dict[str, Any]) -> None:
        with lock:
            if not info:
                info.append(_ns(msg))
        got.set()

    def on_tf(msg: dict[str, Any]) -> None:
        with lock:
            for stamped in _ns(msg).transforms:
                try:
                    tree.add(checked_transform(topics.tf_static_topic, stamped))
                except (InputError, AttributeError):
                    continue
        got.set()

    link.subscribe(topics.camera_info_topic, CAMERA_INFO, on_info)
    link.subscribe(topics.tf_static_topic, TF_MESSAGE, on_tf)
    deadline = time.monotonic() + float(topics.camera_wait)
    camera_msg: Any = None
    mount: tuple[np.ndarray, np.ndarray] | None = None
    while time.monotonic() < deadline:
        got.wait(max(0.0, min(0.1, deadline - time.monotonic())))
        got.clear()
        with lock:
            camera_msg = info[0] if info else None
            if camera_msg is not None:
                try:
                    mount = tree.lookup(base_frame, frame_name(camera_msg.header.frame_id))
                except (InputError, AttributeError, KeyError):
                    mount = None
        if camera_msg is not None and mount is not None:
            break
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
