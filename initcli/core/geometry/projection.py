"""Eq. 1-2: a detected box centre and its depth -> a 3D point in the odometry frame, and back.

Frames (§3.3.1):

- *optical*: the image frame of Eq. 1 -- x right, y down, z forward (along the optical axis).
- *camera body*: the camera as mounted -- x forward, y left, z up (REP 103).
- *base*: the robot base -- x forward, y left, z up; the camera body's pose in it is the log's
  ``camera_pose`` (x, y, z, roll, pitch, yaw; rotation ``Rz(yaw) Ry(pitch) Rx(roll)``).
- *odom*: origin at the start pose, x along the initial heading; the robot base moves in its
  plane (x, y, yaw).

The inverse (:func:`odom_to_pixel`, :func:`box_for_point`) is what the synthetic-log maker
and the simulator use to render a BIM feature as a detection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.se2 import Pose2D

__all__ = [
    "CameraIntrinsics",
    "CameraMount",
    "DEFAULT_CAMERA",
    "DEFAULT_MOUNT",
    "R_BODY_OPTICAL",
    "base_to_odom",
    "bbox_centre",
    "box_for_point",
    "detections_to_odom",
    "mount_from_optical",
    "odom_to_optical",
    "odom_to_pixel",
    "optical_rotation",
    "optical_to_base",
    "optical_to_pixel",
    "pixel_to_optical",
    "rpy_from_matrix",
    "rpy_matrix",
]

# Optical (x right, y down, z forward) -> camera body (x forward, y left, z up).
R_BODY_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics of Eq. 1: focal lengths and image centre in pixels, image size."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int


@dataclass(frozen=True)
class CameraMount:
    """The camera body's pose in the robot base frame (metres, radians)."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0

    def rotation(self) -> np.ndarray:
        """``R_base_body = Rz(yaw) Ry(pitch) Rx(roll)``."""
        return rpy_matrix(self.roll, self.pitch, self.yaw)

    @property
    def translation(self) -> np.ndarray:
        return np.array([self.x, self.y, self.z])


# The camera of the synthetic logs, the simulator and the survey where no config sets one.
DEFAULT_CAMERA = CameraIntrinsics(fx=615.0, fy=615.0, cx=320.0, cy=240.0, width=640, height=480)
DEFAULT_MOUNT = CameraMount(x=0.2, y=0.0, z=1.0, roll=0.0, pitch=0.0, yaw=0.0)


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rotation ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (fixed-axis roll, pitch, yaw as in ROS)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def bbox_centre(bbox: np.ndarray) -> np.ndarray:
    """(N, 4) boxes ``[u1, v1, u2, v2]`` -> (N, 2) centres ``(b_x, b_y)``."""
    b = np.asarray(bbox, dtype=float).reshape(-1, 4)
    return np.column_stack([(b[:, 0] + b[:, 2]) / 2.0, (b[:, 1] + b[:, 3]) / 2.0])


def pixel_to_optical(u: np.ndarray, v: np.ndarray, depth: np.ndarray, camera: CameraIntrinsics) -> np.ndarray:
    """Eq. 1: pixel ``(b_x, b_y)`` and mean depth ``D`` -> point in the optical frame, (N, 3)."""
    u, v, depth = (np.asarray(a, dtype=float).reshape(-1) for a in (u, v, depth))
    x_c = (u - camera.cx) * depth / camera.fx  # Eq. 1 (separate fx, fy instead of one f)
    y_c = (v - camera.cy) * depth / camera.fy  # Eq. 1
    z_c = depth  # Eq. 1
    return np.column_stack([x_c, y_c, z_c])


def optical_to_base(points: np.ndarray, mount: CameraMount) -> np.ndarray:
    """Eq. 2, first transforms: optical -> camera body -> robot base, (N, 3)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    r = mount.rotation() @ R_BODY_OPTICAL  # T^{base}_{optical} = T^{base}_{body} T^{body}_{optical}
    base: np.ndarray = p @ r.T + mount.translation
    return base


def base_to_odom(points: np.ndarray, robot: Pose2D) -> np.ndarray:
    """Eq. 2, last transform: robot base -> odometry frame (planar robot pose; z is kept)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    xy = robot.apply(p[:, :2])
    return np.column_stack([xy, p[:, 2]])


def detections_to_odom(
    bboxes: np.ndarray, depths: np.ndarray, camera: CameraIntrinsics, mount: CameraMount, robot: Pose2D
) -> np.ndarray:
    """Eq. 1-2: boxes ``[u1, v1, u2, v2]`` with their mean depth -> (N, 3) points in the odom frame."""
    centres = bbox_centre(bboxes)
    optical = pixel_to_optical(centres[:, 0], centres[:, 1], depths, camera)  # Eq. 1
    return base_to_odom(optical_to_base(optical, mount), robot)  # Eq. 2


# --- inverse of Eq. 1-2 (for synthetic logs and the simulator) ---------------------------------


def odom_to_optical(points: np.ndarray, mount: CameraMount, robot: Pose2D) -> np.ndarray:
    """Inverse of Eq. 2: odom points (N, 3) -> optical frame (N, 3)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    base_xy = robot.apply_inverse(p[:, :2])
    base = np.column_stack([base_xy, p[:, 2]])
    r = mount.rotation() @ R_BODY_OPTICAL
    optical: np.ndarray = (base - mount.translation) @ r  # r^T applied to row vectors
    return optical


def optical_to_pixel(
    points: np.ndarray, camera: CameraIntrinsics
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of Eq. 1: optical points (N, 3) -> pixel u, v and depth D (= z_c)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    z = p[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = camera.fx * p[:, 0] / z + camera.cx
        v = camera.fy * p[:, 1] / z + camera.cy
    return u, v, z


def odom_to_pixel(
    points: np.ndarray, camera: CameraIntrinsics, mount: CameraMount, robot: Pose2D
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of Eq. 1-2: odom points (N, 3) -> pixel u, v and depth D; D <= 0 is behind the camera."""
    return optical_to_pixel(odom_to_optical(points, mount, robot), camera)


def box_for_point(
    u: float, v: float, depth: float, width_m: float, height_m: float, camera: CameraIntrinsics
) -> tuple[float, float, float, float]:
    """A box ``[u1, v1, u2, v2]`` centred on pixel (u, v) for an object of the given size at ``depth``.

    The box centre is exactly (u, v), so Eq. 1 applied to it returns the rendered point.
    """
    half_w = 0.5 * camera.fx * width_m / depth
    half_h = 0.5 * camera.fy * height_m / depth
    return (u - half_w, v - half_h, u + half_w, v + half_h)


# --- the camera mount from and to a ROS transform (base frame -> optical frame) ------------------


def rpy_from_matrix(r: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) with ``rpy_matrix(roll, pitch, yaw) == r`` (pitch in [-pi/2, pi/2])."""
    r = np.asarray(r, dtype=float)
    pitch = math.asin(max(-1.0, min(1.0, -r[2, 0])))
    if abs(r[2, 0]) < 1.0 - 1e-9:
        roll = math.atan2(r[2, 1], r[2, 2])
        yaw = math.atan2(r[1, 0], r[0, 0])
    else:  # gimbal lock: roll and yaw share one axis; put it all in yaw
        roll = 0.0
        yaw = math.atan2(-r[0, 1], r[1, 1])
    return roll, pitch, yaw


def mount_from_optical(rotation: np.ndarray, translation: np.ndarray) -> CameraMount:
    """The camera body's pose in the base frame from the optical frame's pose in it.

    ``rotation`` is ``R^{base}_{optical}`` (columns: the optical x right, y down, z forward axes in
    the base frame), e.g. the ``/tf_static`` chain ``base_link -> camera_color_optical_frame``.
    ``R^{base}_{body} = R^{base}_{optical} (R^{body}_{optical})^T`` (the inverse of Eq. 2's first step).
    """
    r_body = np.asarray(rotation, dtype=float) @ R_BODY_OPTICAL.T
    roll, pitch, yaw = rpy_from_matrix(r_body)
    x, y, z = (float(v) for v in np.asarray(translation, dtype=float).reshape(3))
    return CameraMount(x, y, z, roll, pitch, yaw)


def optical_rotation(mount: CameraMount) -> np.ndarray:
    """``R^{base}_{optical}`` of a mount (Eq. 2: body rotation times the optical-to-body axes)."""
    rotation: np.ndarray = mount.rotation() @ R_BODY_OPTICAL
    return rotation
