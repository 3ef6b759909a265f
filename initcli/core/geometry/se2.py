"""Planar poses and SE(2) helpers shared by every other core module.

Conventions: angles in radians, counter-clockwise positive; a :class:`Pose2D` ``(x, y, yaw)``
of frame B expressed in frame A maps points from B to A: ``p_A = R(yaw) p_B + (x, y)``
(the matrix of Eq. 11).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import overload

import numpy as np

__all__ = [
    "MATCH_DIGITS",
    "SESSION_DIGITS",
    "Pose2D",
    "PoseDigits",
    "pose_json",
    "poses_to_array",
    "rot2",
    "transform_poses",
    "wrap_angle",
]


@overload
def wrap_angle(angle: float) -> float: ...
@overload
def wrap_angle(angle: np.ndarray) -> np.ndarray: ...
def wrap_angle(angle: float | np.ndarray) -> float | np.ndarray:
    """Wrap an angle (or an array of angles) to [-pi, pi)."""
    if isinstance(angle, float | int):  # the same float64 arithmetic, without numpy's call overhead
        return (angle + math.pi) % (2.0 * math.pi) - math.pi
    wrapped = (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi
    if np.ndim(wrapped) == 0:
        return float(wrapped)
    return wrapped


def rot2(theta: float) -> np.ndarray:
    """The 2x2 rotation matrix R(theta)."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class Pose2D:
    """A planar pose ``(x, y, yaw)``; also used as the rigid transform it defines (Eq. 11)."""

    x: float
    y: float
    yaw: float

    @staticmethod
    def identity() -> Pose2D:
        return Pose2D(0.0, 0.0, 0.0)

    @staticmethod
    def from_matrix(matrix: np.ndarray) -> Pose2D:
        """From a 3x3 homogeneous matrix (the rotation part must be a rotation)."""
        return Pose2D(float(matrix[0, 2]), float(matrix[1, 2]), math.atan2(matrix[1, 0], matrix[0, 0]))

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])

    def matrix(self) -> np.ndarray:
        """The 3x3 homogeneous matrix of Eq. 11."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, -s, self.x], [s, c, self.y], [0.0, 0.0, 1.0]])

    def compose(self, other: Pose2D) -> Pose2D:
        """``self * other``: ``other`` expressed in the frame ``self`` is expressed in."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2D(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            float(wrap_angle(self.yaw + other.yaw)),
        )

    def __mul__(self, other: Pose2D) -> Pose2D:
        return self.compose(other)

    def inverse(self) -> Pose2D:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2D(-(c * self.x + s * self.y), -(-s * self.x + c * self.y), float(wrap_angle(-self.yaw)))

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Map points (N x 2, or one point of shape (2,)) from this pose's frame to the parent frame."""
        pts = np.asarray(points, dtype=float)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x = c * pts[..., 0] - s * pts[..., 1] + self.x
        y = s * pts[..., 0] + c * pts[..., 1] + self.y
        return np.stack([x, y], axis=-1)

    def apply_inverse(self, points: np.ndarray) -> np.ndarray:
        """Map points from the parent frame into this pose's frame."""
        pts = np.asarray(points, dtype=float)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        dx, dy = pts[..., 0] - self.x, pts[..., 1] - self.y
        return np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)

    def distance_to(self, other: Pose2D) -> float:
        return math.hypot(self.x - other.x, self.y - other.y)

    def yaw_error(self, other: Pose2D) -> float:
        """Absolute heading difference in radians, in [0, pi]."""
        return abs(float(wrap_angle(self.yaw - other.yaw)))

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.yaw)


def poses_to_array(poses: list[Pose2D]) -> np.ndarray:
    """N poses -> (N, 3) array of x, y, yaw."""
    if not poses:
        return np.zeros((0, 3))
    return np.array([p.as_tuple() for p in poses], dtype=float)


def transform_poses(transform: Pose2D, poses: np.ndarray) -> np.ndarray:
    """Apply a rigid transform to an (N, 3) array of poses (x, y, yaw): ``transform * pose`` for
    each, the same float64 arithmetic as :meth:`Pose2D.compose`."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    c, s = math.cos(transform.yaw), math.sin(transform.yaw)
    x, y = poses[:, 0], poses[:, 1]
    return np.column_stack(
        [transform.x + c * x - s * y, transform.y + s * x + c * y, wrap_angle(transform.yaw + poses[:, 2])]
    )


@dataclass(frozen=True)
class PoseDigits:
    """The decimal places a pose is written to JSON with: x and y (m), yaw (rad), yaw_deg (degrees)."""

    xy: int
    yaw: int
    yaw_deg: int


# The two roundings the JSON documents use, each for every pose of its documents:
MATCH_DIGITS = PoseDigits(xy=6, yaw=6, yaw_deg=4)  # bim-init match --json (match_result.schema.json)
SESSION_DIGITS = PoseDigits(xy=4, yaw=5, yaw_deg=3)  # summary.json: the session's poses, the delivered one


def pose_json(pose: Pose2D, digits: PoseDigits) -> dict[str, float]:
    """``pose`` as a JSON object ``{x, y, yaw, yaw_deg}``, rounded to ``digits`` (:data:`MATCH_DIGITS`
    or :data:`SESSION_DIGITS`, the rounding of the document it goes in)."""
    return {
        "x": round(pose.x, digits.xy),
        "y": round(pose.y, digits.xy),
        "yaw": round(pose.yaw, digits.yaw),
        "yaw_deg": round(math.degrees(pose.yaw), digits.yaw_deg),
    }
