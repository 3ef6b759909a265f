"""BIM-based rectification (§3.3.5, Eq. 17): keep the estimated robot position off the walls.

The wall surfaces come from ``walls.geojson`` (segments with a unit normal pointing into free
space). For the estimated position (x_g, y_g):

1. the perpendicular (signed, along the normal) distance to every wall whose perpendicular foot
   falls on the segment is computed and the nearest wall (smallest absolute distance) chosen;
2. if that distance d_wall is below d_thre (the wall-following clearance; negative means behind
   the surface, i.e. inside the wall), the point is moved along the normal to the clearance line:
   (x_adj, y_adj) = (x_g, y_g) + (d_thre - d_wall) n_w;
3. Eq. 17: on the clearance line n_w . (p - p_adj) = 0, the point whose distance to the last
   matched feature (o_bx, o_by) is the measured d_o and that is closest to (x_adj, y_adj). If the
   circle does not reach the line, the point of the line closest to the circle is taken.

The heading is then recomputed from the last feature with Eq. 13 (:func:`rectify_pose`). Beyond
the paper, a rectification that turns the heading by more than ``max_turn`` (the matcher passes
Eq. 9's orientation tolerance beta) is dropped and the pose kept as it is: Eq. 13 from one feature
at a moved position is then unreliable. In 350 construction claims on the three samples (doors
built off their place), 8 of the 10 rectifications that turned the heading by 15 degrees or more
made it worse (median heading error 1.9 -> 40 degrees), and one turned a right pose by 174 degrees
into a point-symmetric lobby's wrong place that passed every check (ntu_hallway, 40 % of doors
missing, seed 28).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.hypotheses.pose import heading_from_feature

__all__ = ["Rectification", "WallArray", "nearest_wall", "rectify_pose", "rectify_position"]


@dataclass(frozen=True)
class WallArray:
    """Wall surfaces as arrays: endpoints p1, p2 (W, 2) and unit normals into free space (W, 2)."""

    p1: np.ndarray
    p2: np.ndarray
    normal: np.ndarray

    @staticmethod
    def from_segments(segments: list[tuple[float, float, float, float, float, float]]) -> WallArray:
        """From (x1, y1, x2, y2, nx, ny) tuples; normals are normalised."""
        a = np.asarray(segments, dtype=float).reshape(-1, 6)
        n = a[:, 4:6]
        norm = np.linalg.norm(n, axis=1, keepdims=True)
        n = np.divide(n, norm, out=np.zeros_like(n), where=norm > 0)
        return WallArray(a[:, 0:2].copy(), a[:, 2:4].copy(), n)

    def __len__(self) -> int:
        return len(self.p1)


@dataclass(frozen=True)
class Rectification:
    position: np.ndarray  # rectified (x, y)
    moved: bool
    wall: int  # index of the nearest wall, -1 if none
    d_wall: float  # signed distance to it before rectification (nan if none)


def nearest_wall(point: np.ndarray, walls: WallArray) -> tuple[int, float]:
    """Index of the nearest wall by perpendicular distance and the signed distance (along its normal)."""
    if len(walls) == 0:
        return -1, math.nan
    p = np.asarray(point, dtype=float).reshape(2)
    seg = walls.p2 - walls.p1
    length2 = np.einsum("ij,ij->i", seg, seg)
    rel = p - walls.p1
    t = np.divide(np.einsum("ij,ij->i", rel, seg), length2, out=np.full(len(seg), -1.0), where=length2 > 0)
    signed = np.einsum("ij,ij->i", rel, walls.normal)  # perpendicular distance along the surface normal
    valid = (t >= 0.0) & (t <= 1.0) & (np.abs(walls.normal).sum(axis=1) > 0)
    if not valid.any():
        return -1, math.nan
    candidates = np.flatnonzero(valid)
    best = candidates[np.argmin(np.abs(signed[candidates]))]
    return int(best), float(signed[best])


def rectify_position(
    position: np.ndarray, walls: WallArray, d_thre: float, feature_bim: np.ndarray, d_o: float
) -> Rectification:
    """Eq. 17 for one position; ``d_o`` is the measured distance to the last feature ``feature_bim``."""
    g = np.asarray(position, dtype=float).reshape(2)
    index, d_wall = nearest_wall(g, walls)
    if index < 0 or d_wall >= d_thre:
        return Rectification(g.copy(), False, index, d_wall)
    n = walls.normal[index]
    adj = g + (d_thre - d_wall) * n  # (x_adj, y_adj): moved out to the clearance d_thre
    tangent = np.array([-n[1], n[0]])  # the clearance line is adj + lambda * tangent (n . (p - adj) = 0)
    o = np.asarray(feature_bim, dtype=float).reshape(2)
    b = float(tangent @ (adj - o))
    c = float((adj - o) @ (adj - o)) - d_o * d_o
    disc = b * b - c
    if disc >= 0.0:  # Eq. 17: closest of the two line-circle intersections
        root = math.sqrt(disc)
        lam = min((-b + root, -b - root), key=abs)
    else:  # the circle does not reach the line: closest point of the line to the circle
        lam = -b
    return Rectification(adj + lam * tangent, True, index, d_wall)


def rectify_pose(
    pose: Pose2D,
    walls: WallArray,
    d_thre: float,
    feature_bim: np.ndarray,
    feature_robot: np.ndarray,
    max_turn: float = math.pi,
) -> tuple[Pose2D, Rectification]:
    """Eq. 17 on the position, then the heading again from the last feature (Eq. 13).

    ``feature_robot`` is the last matched feature in the robot frame (o_rx, o_ry); its norm is d_o.
    A rectified heading more than ``max_turn`` (rad) from the pose's drops the rectification (the
    pose is returned as it is, ``moved`` False).
    """
    d_o = float(np.hypot(*np.asarray(feature_robot, dtype=float)))
    rect = rectify_position(pose.xy, walls, d_thre, feature_bim, d_o)
    if not rect.moved:
        return pose, rect
    yaw = heading_from_feature(rect.position, feature_bim, feature_robot)  # Eq. 13 at the new position
    rectified = Pose2D(float(rect.position[0]), float(rect.position[1]), float(wrap_angle(yaw)))
    if rectified.yaw_error(pose) > max_turn:
        return pose, Rectification(pose.xy.copy(), False, rect.wall, rect.d_wall)
    return rectified, rect
