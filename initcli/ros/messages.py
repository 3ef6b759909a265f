"""The contents of ROS messages as numbers: stamps, colour and depth images, intrinsics and
transforms, with NaN or infinity refused naming the topic (a detection log holds finite numbers)."""

from __future__ import annotations

import math
from typing import Any

import cv2
import numpy as np

from bimkit.cli import native_stderr_silenced
from bimkit.errors import InputError
from initcli.core.geometry.projection import CameraIntrinsics
from initcli.ros.tf import msg_transform

__all__ = ["checked_transform", "decode_depth", "decode_image", "finite", "intrinsics", "stamp_seconds"]


def stamp_seconds(msg: Any, bag_ns: int) -> float:
    """The header stamp in seconds; the bag's receive time when the stamp was never set."""
    header = getattr(msg, "header", None)
    if header is not None:
        st = header.stamp
        sec: Any = getattr(st, "sec", None)  # the message types are not typed
        nsec: Any = getattr(st, "nanosec", None)
        if sec is None:  # ROS 1 spelling
            sec, nsec = getattr(st, "secs", 0), getattr(st, "nsecs", 0)
        if sec or nsec:
            return int(sec) + int(nsec) * 1e-9
    return bag_ns * 1e-9


def decode_image(msg: Any) -> np.ndarray:
    """sensor_msgs/Image or CompressedImage -> BGR uint8 (H, W, 3)."""
    if hasattr(msg, "format"):  # CompressedImage
        with native_stderr_silenced():  # libpng's complaints about a broken image: our one line
            img = cv2.imdecode(np.frombuffer(bytes(msg.data), np.uint8), cv2.IMREAD_COLOR)
        if img is None:
            raise InputError(f"a CompressedImage ({msg.format}) could not be decoded")
        return img
    enc = str(msg.encoding).lower()
    h, w = int(msg.height), int(msg.width)
    data = np.frombuffer(bytes(msg.data), np.uint8)
    channels = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1, "8uc1": 1, "8uc3": 3}.get(enc)
    if channels is None:
        raise InputError(
            f"image encoding {msg.encoding!r} is not supported (rgb8, bgr8, rgba8, bgra8, mono8)"
        )
    step = int(msg.step) or w * channels
    img = data[: h * step].reshape(h, step)[:, : w * channels].reshape(h, w, channels)
    if enc in ("rgb8",):
        return cv2.cvtColor(img, cv2.COLOR_RGB2BGR)
    if enc == "rgba8":
        return cv2.cvtColor(img, cv2.COLOR_RGBA2BGR)
    if enc == "bgra8":
        return cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
    if channels == 1:
        return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    return np.ascontiguousarray(img)


def decode_depth(msg: Any) -> np.ndarray:
    """An aligned depth image -> metres, float32 (H, W); 0 where the camera had no return."""
    enc = str(msg.encoding)
    h, w = int(msg.height), int(msg.width)
    raw = bytes(msg.data)
    order = ">" if int(getattr(msg, "is_bigendian", 0)) else "<"
    if enc in ("16UC1", "mono16"):
        dtype, scale = np.dtype(f"{order}u2"), 1e-3  # millimetres
    elif enc == "32FC1":
        dtype, scale = np.dtype(f"{order}f4"), 1.0  # metres
    else:
        raise InputError(f"depth image encoding {enc!r}: expected 16UC1 (mm) or 32FC1 (m)")
    step = int(msg.step) or w * dtype.itemsize
    rows = np.frombuffer(raw[: h * step], np.uint8).reshape(h, step)[:, : w * dtype.itemsize]
    values = np.ascontiguousarray(rows).view(dtype).reshape(h, w).astype(np.float32)
    return values * np.float32(scale) if scale != 1.0 else values


def finite(topic: str, what: str, *values: float) -> None:
    """NaN or infinity in a message is one line naming the topic (a log holds finite numbers only)."""
    for v in values:
        if not math.isfinite(float(v)):
            raise InputError(f"{topic}: {what} holds {float(v)} (NaN or infinity)")


def intrinsics(msg: Any, topic: str = "camera_info") -> CameraIntrinsics:
    k = [float(v) for v in (msg.k if hasattr(msg, "k") else msg.K)]
    finite(topic, "the CameraInfo K matrix", *k)
    cam = CameraIntrinsics(fx=k[0], fy=k[4], cx=k[2], cy=k[5], width=int(msg.width), height=int(msg.height))
    if cam.fx <= 0 or cam.fy <= 0 or cam.width <= 0 or cam.height <= 0:
        raise InputError("camera_info has no intrinsics (K is zero or the size is 0)")
    return cam


def checked_transform(topic: str, stamped: Any) -> Any:
    tr = stamped.transform
    q, p = tr.rotation, tr.translation
    finite(topic, f"the transform to {stamped.child_frame_id!r}", q.x, q.y, q.z, q.w, p.x, p.y, p.z)
    return msg_transform(stamped)
