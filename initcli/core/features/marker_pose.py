"""The robot pose one decoded ArUco tag gives (the marker baseline of §4.3): the tag's corner
geometry and the IPPE pose of the tag in the camera, chained to the robot's base on the floor.

Frames: the BIM frame is the world (x, y on the floor plan, z up); the camera conventions are
those of :mod:`initcli.core.geometry.projection` (optical: x right, y down, z forward). A tag's own frame is
OpenCV's ArUco frame: origin at the tag centre, x to the right and y up as a viewer in front of the
tag sees it, z out of the wall (along the wall normal, into free space). With homogeneous
transforms ``T_a_b`` (frame b in frame a):

    T_bim_base = T_bim_marker inv(T_optical_marker) inv(T_base_optical),
    T_base_optical = T_base_body T_body_optical,

where ``T_optical_marker`` is ``cv2.solvePnP``'s answer for the tag's 4 corner pixels.
"""

from __future__ import annotations

import math
from typing import Protocol

import cv2
import numpy as np

from initcli.core.geometry.least_squares import levenberg_marquardt
from initcli.core.geometry.projection import R_BODY_OPTICAL, CameraIntrinsics, CameraMount, odom_to_pixel
from initcli.core.geometry.se2 import Pose2D, wrap_angle

__all__ = ["Tag", "robot_pose_from_marker", "tag_object_points", "tag_rotation"]


class Tag(Protocol):
    """What the pose needs of a tag: its BIM pose (centre and wall normal) and its corner geometry."""

    @property
    def centre(self) -> np.ndarray: ...

    def rotation(self) -> np.ndarray: ...

    def object_points(self) -> np.ndarray: ...


def tag_rotation(normal: tuple[float, float]) -> np.ndarray:
    """``R_bim_marker`` of a tag on a vertical wall with (unit) ``normal``: columns are the tag's x
    (right), y (up) and z (out of the wall) axes in the BIM frame."""
    nx, ny = normal
    return np.array([[-ny, 0.0, nx], [nx, 0.0, ny], [0.0, 1.0, 0.0]])


def tag_object_points(size: float) -> np.ndarray:
    """The 4 corners of a tag of side ``size`` in its own frame, in the order
    ``SOLVEPNP_IPPE_SQUARE`` expects: top-left, top-right, bottom-right, bottom-left."""
    h = size / 2.0
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])


def robot_pose_from_marker(
    corners_px: np.ndarray, marker: Tag, intrinsics: CameraIntrinsics, mount: CameraMount
) -> Pose2D:
    """The robot's planar pose in the BIM frame from one decoded tag (§4.3).

    ``cv2.solvePnP(..., SOLVEPNP_IPPE_SQUARE)`` gives ``T_optical_marker``; with the tag's BIM pose
    ``T_bim_marker`` and the mount ``T_base_optical = T_base_body T_body_optical``:
    ``T_bim_base = T_bim_marker inv(T_optical_marker) inv(T_base_optical)``, projected on the floor
    (x, y, and the heading of the base's x axis).

    A small tag seen head-on from afar has two 6-DOF solutions that reproject almost equally well:
    the true one and its mirror, tilted about the tag's plane; picking the lower reprojection error
    (ArUco's ``estimatePoseSingleMarkers``) then often picks the mirror, a pose metres off. The robot
    knows more: its base stands level on the floor with the camera at its known mount, and the tag
    hangs vertically on a wall. So each 6-DOF candidate (IPPE's two, and ``SOLVEPNP_ITERATIVE``'s,
    since IPPE is numerically degenerate for a noise-free image of a vertical tag from a level
    camera) only seeds a 3-DOF fit: the planar pose (x, y, yaw) that minimises the corners'
    reprojection error (inverse Eq. 1-2). The mirror has no level counterpart and falls away.
    """
    k = np.array([[intrinsics.fx, 0.0, intrinsics.cx], [0.0, intrinsics.fy, intrinsics.cy], [0.0, 0.0, 1.0]])
    pixels = np.asarray(corners_px, dtype=np.float64).reshape(4, 2)
    corners = marker.object_points() @ marker.rotation().T + marker.centre  # (4, 3) in the BIM frame
    t_bim_marker = _homogeneous(marker.rotation(), marker.centre)
    t_base_opt = _homogeneous(mount.rotation() @ R_BODY_OPTICAL, mount.translation)

    def residuals(q: np.ndarray) -> np.ndarray:
        u, v, depth = odom_to_pixel(corners, intrinsics, mount, Pose2D(float(q[0]), float(q[1]), float(q[2])))
        if np.any(depth <= 0):
            return np.full(8, 1e3)
        return np.concatenate([u - pixels[:, 0], v - pixels[:, 1]])

    best: tuple[float, np.ndarray] | None = None
    solutions = _tag_solutions(marker.object_points(), pixels, k)
    if not solutions:
        raise ValueError("solvePnP found no pose for the tag")
    for _, _, rvec, tvec in solutions:
        t_opt_marker = _homogeneous(cv2.Rodrigues(rvec)[0], tvec.reshape(3))
        t_bim_base = t_bim_marker @ np.linalg.inv(t_opt_marker) @ np.linalg.inv(t_base_opt)
        seed = np.array([t_bim_base[0, 3], t_bim_base[1, 3], math.atan2(t_bim_base[1, 0], t_bim_base[0, 0])])
        fit = levenberg_marquardt(residuals, seed)
        cost = float(np.sum(fit.fun**2))
        if best is None or cost < best[0]:
            best = (cost, fit.x)
    assert best is not None
    x, y, yaw = best[1]
    return Pose2D(float(x), float(y), float(wrap_angle(float(yaw))))


def _tag_solutions(
    objects: np.ndarray, pixels: np.ndarray, k: np.ndarray
) -> list[tuple[float, int, np.ndarray, np.ndarray]]:
    """``(reprojection error px^2, order, rvec, tvec)`` of every ``T_optical_marker`` candidate: IPPE
    square's solutions and the iterative one (see :func:`robot_pose_from_marker`)."""
    objects = objects.astype(np.float64).reshape(4, 1, 3)
    pixels = pixels.reshape(4, 1, 2)
    solutions: list[tuple[np.ndarray, np.ndarray]] = []
    n, rvecs, tvecs, _ = cv2.solvePnPGeneric(objects, pixels, k, None, flags=cv2.SOLVEPNP_IPPE_SQUARE)
    solutions += [(rvecs[i], tvecs[i]) for i in range(n)]
    ok, rvec, tvec = cv2.solvePnP(objects, pixels, k, None, flags=cv2.SOLVEPNP_ITERATIVE)
    if ok:
        solutions.append((rvec, tvec))
    out = []
    for order, (rvec, tvec) in enumerate(solutions):
        projected, _ = cv2.projectPoints(objects, rvec, tvec, k, None)
        error = float(np.sum((projected.reshape(4, 2) - pixels.reshape(4, 2)) ** 2))
        out.append((error, order, rvec, tvec))
    return out


def _homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = rotation
    t[:3, 3] = translation
    return t
