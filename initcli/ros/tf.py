"""Quaternions and the transform tree of ``/tf_static`` (base frame -> camera optical frame)."""

from __future__ import annotations

import math

import numpy as np

from bimkit.errors import InputError
from initcli.ros.records import Transform

__all__ = [
    "TransformTree",
    "frame_name",
    "matrix_quaternion",
    "msg_transform",
    "quaternion_matrix",
    "quaternion_yaw",
    "yaw_quaternion",
]


def quaternion_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Rotation matrix of a unit quaternion (normalised first)."""
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n < 1e-12:
        raise InputError("a transform has a zero quaternion")
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_quaternion(r: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation matrix (w >= 0)."""
    r = np.asarray(r, dtype=float)
    t = np.trace(r)
    if t > 0:
        s = 2.0 * math.sqrt(t + 1.0)
        q = (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 1e-300))
        v = [0.0, 0.0, 0.0]
        v[i] = 0.25 * s
        v[j] = (r[j, i] + r[i, j]) / s
        v[k] = (r[k, i] + r[i, k]) / s
        q = v[0], v[1], v[2], (r[k, j] - r[j, k]) / s
    if q[3] < 0:
        q = tuple(-c for c in q)  # type: ignore[assignment]
    return float(q[0]), float(q[1]), float(q[2]), float(q[3])


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def quaternion_yaw(x: float, y: float, z: float, w: float) -> float:
    """Heading (rotation about z) of a quaternion."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def frame_name(name: str) -> str:
    """ROS 1 frames may start with '/'; compare without it."""
    return name.strip().lstrip("/")


def msg_transform(stamped: object) -> Transform:
    """A ``geometry_msgs/TransformStamped`` as a :class:`Transform`."""
    tr = stamped.transform  # type: ignore[attr-defined]
    q, p = tr.rotation, tr.translation
    return Transform(
        frame_name(stamped.header.frame_id),  # type: ignore[attr-defined]
        frame_name(stamped.child_frame_id),  # type: ignore[attr-defined]
        quaternion_matrix(q.x, q.y, q.z, q.w),
        np.array([p.x, p.y, p.z], dtype=float),
    )


class TransformTree:
    """Static transforms, each child with one parent; :meth:`lookup` chains them."""

    def __init__(self) -> None:
        self.edges: dict[str, Transform] = {}

    def add(self, transform: Transform) -> None:
        self.edges[transform.child] = transform

    def _to_root(self, frame: str) -> list[str]:
        chain = [frame]
        while chain[-1] in self.edges and len(chain) < 64:
            chain.append(self.edges[chain[-1]].parent)
        return chain

    def _from_root(self, frame: str, stop: str) -> tuple[np.ndarray, np.ndarray]:
        """Pose of ``frame`` in its ancestor ``stop``."""
        r, t = np.eye(3), np.zeros(3)
        while frame != stop:
            e = self.edges[frame]
            r, t = e.rotation @ r, e.rotation @ t + e.translation
            frame = e.parent
        return r, t

    def lookup(self, parent: str, child: str) -> tuple[np.ndarray, np.ndarray]:
        """Pose of ``child`` in ``parent`` (rotation, translation); InputError when not connected."""
        parent, child = frame_name(parent), frame_name(child)
        up_child, up_parent = self._to_root(child), self._to_root(parent)
        common = next((f for f in up_child if f in up_parent), None)
        if common is None:
            known = sorted(set(self.edges) | {e.parent for e in self.edges.values()})
            raise InputError(
                f"no transform {parent} -> {child} in /tf_static (frames: {', '.join(known) or 'none'}); "
                "use --base-frame or record /tf_static"
            )
        r_c, t_c = self._from_root(child, common)
        r_p, t_p = self._from_root(parent, common)
        return r_p.T @ r_c, r_p.T @ (t_c - t_p)
