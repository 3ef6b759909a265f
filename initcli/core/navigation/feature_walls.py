"""Which wall to head for on an open floor (beyond the paper): the doors, lifts and stairs are on
the walls.

From the façade of an open-plan office or a car park the camera does not reach the doors across
the floor. Each pose hypothesis puts the BIM's features it has not matched yet somewhere in the
robot's frame; a wall the lidar sees across the floor that holds such a feature under many
hypotheses is where a look is worth the drive, whichever hypothesis is right
(:func:`toward_feature_wall`). Before the hypotheses say anything, a robot that went round a
column heads for the nearest long wall its path has not followed (:func:`toward_long_wall`). Pure
numpy: the session (:mod:`initcli.session.looks`, :mod:`initcli.session.escapes`) builds the
predictions from its hypotheses and the path from its odometry.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from initcli.core.navigation.wall_following import CROSS_SHORT, CROSS_WALL_M, ScanView, wall_ahead, wall_width

__all__ = [
    "FEATURE_WALL_BEARINGS",
    "FEATURE_WALL_HOLD",
    "FEATURE_WALL_MIN_REACH",
    "LONG_WALL_M",
    "toward_feature_wall",
    "toward_long_wall",
]

FEATURE_WALL_BEARINGS = np.radians(np.arange(-180.0, 180.0, 10.0))  # rad, robot frame: the ways tried
FEATURE_WALL_HOLD = 3.0  # m: a predicted feature this close to where the lidar hit the wall is on it
FEATURE_WALL_MIN_REACH = 3.0  # m: a crossing shorter than this is not worth it
LONG_WALL_M = 4.0  # m: a wall the lidar sees this wide is a long one (a column is under 1 m)
LONG_WALL_MIN_REACH = 1.0  # m: a long wall nearer than this is the one the robot is at
FOLLOWED_M = 1.5  # m: the path came this close to where the lidar hit a wall: that wall was followed
FEATURE_WALL_SEEN = 4.0  # m: a predicted feature this near the robot or its path, facing it, was in view


def toward_feature_wall(
    scan: ScanView,
    points: np.ndarray,
    normals: np.ndarray,
    hypothesis: np.ndarray,
    been: np.ndarray | None = None,
    passed: np.ndarray | None = None,
) -> tuple[float, float, int] | None:
    """(bearing rad, reach m, hypotheses) of the way across the floor to the wall that holds a feature
    not yet seen under the most hypotheses; None when no such wall is in the lidar's view.

    ``points`` (N x 2) and ``normals`` (N x 2) are the unmatched BIM features of the hypotheses in
    the robot's frame, ``hypothesis`` (N,) the hypothesis each belongs to. A way counts when
    :func:`wall_ahead` finds a wall along it, at least FEATURE_WALL_MIN_REACH m on, and that wall
    is CROSS_WALL_M or more wide
    (:func:`wall_width`: not a column, round which the robot would circle on the open floor). A
    feature counts for it when it lies within FEATURE_WALL_HOLD m of that hit, faces the crossing's
    end (its normal toward it), and is FEATURE_WALL_SEEN m or more from the robot and from every
    point of ``passed`` (K x 2, robot frame: the path driven so far) that it faces: the look here or
    the drive past there had it in view, and crossing back to a wall already driven along finds
    nothing new. A way that ends within FEATURE_WALL_HOLD m of a point in ``been`` (M x 2, robot
    frame: where earlier such crossings ended) is not taken again. Among the ways counted by most
    hypotheses, the shortest wins."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    normals = np.asarray(normals, dtype=float).reshape(-1, 2)
    hypothesis = np.asarray(hypothesis).reshape(-1)
    views = np.vstack([np.zeros((1, 2)), np.asarray(passed if passed is not None else []).reshape(-1, 2)])
    offsets = views[None, :, :] - points[:, None, :]  # N x K: feature -> where the robot was
    near = np.hypot(offsets[..., 0], offsets[..., 1]) < FEATURE_WALL_SEEN
    in_front = np.einsum("nkj,nj->nk", offsets, normals) > 0.0
    far = ~(near & in_front).any(axis=1)
    points, normals, hypothesis = points[far], normals[far], hypothesis[far]
    if len(points) == 0:
        return None
    been = np.asarray(been if been is not None else np.empty((0, 2)), dtype=float).reshape(-1, 2)
    best: tuple[int, float, float] | None = None  # (hypotheses, -reach, bearing)
    # not a column nor a row of them (under CROSS_WALL_M): no wall to follow on from there
    for bearing, clear, reach, _ in _ways_to_walls(scan, FEATURE_WALL_MIN_REACH, CROSS_WALL_M):
        direction = np.array([math.cos(bearing), math.sin(bearing)])
        wall, end = clear * direction, reach * direction
        if len(been) and np.hypot(*(been - end).T).min() <= FEATURE_WALL_HOLD:
            continue
        on_wall = np.hypot(*(points - wall).T) <= FEATURE_WALL_HOLD
        facing = np.einsum("ij,ij->i", end - points, normals) > 0.0
        count = len(np.unique(hypothesis[on_wall & facing]))
        if count and (best is None or (count, -reach) > best[:2]):
            best = (count, -reach, float(bearing))
    if best is None:
        return None
    return best[2], -best[1], best[0]


def toward_long_wall(scan: ScanView, passed: np.ndarray | None = None) -> tuple[float, float] | None:
    """(bearing rad, reach m) of the way to the nearest long wall the path has not followed, before
    any hypothesis says where the features are: on an open floor among columns the wall follower
    goes round a column and the escapes send it to the openings of the floor in the middle, where
    it circles the next one; the doors and stairs are on the walls. A way counts as in
    :func:`toward_feature_wall` (:func:`wall_ahead`, LONG_WALL_MIN_REACH m or more on) when the
    wall it hits is LONG_WALL_M or more wide
    (:func:`wall_width`) and no point of ``passed`` (K x 2, robot frame: the path so far) came within
    FOLLOWED_M of the hit. The shortest such way; None when there is none."""
    passed = np.asarray(passed if passed is not None else np.empty((0, 2)), dtype=float).reshape(-1, 2)
    x, y = scan.xy
    best: tuple[float, float] | None = None  # (reach, bearing)
    for bearing, _, reach, hit in _ways_to_walls(scan, LONG_WALL_MIN_REACH, LONG_WALL_M):
        if best is not None and reach >= best[0]:
            continue
        if len(passed) and np.hypot(*(passed - np.array([x[hit], y[hit]])).T).min() <= FOLLOWED_M:
            continue
        best = (reach, bearing)
    return None if best is None else (best[1], best[0])


def _ways_to_walls(
    scan: ScanView, min_reach: float, min_width: float
) -> Iterator[tuple[float, float, float, int]]:
    """The ways of FEATURE_WALL_BEARINGS across the floor to a wall (:func:`wall_ahead`) that reach
    ``min_reach`` m or more (stopping CROSS_SHORT short of it) and whose wall is ``min_width`` m or
    more wide (:func:`wall_width`): (bearing rad, clear m, reach m, the beam that hit it)."""
    for bearing in FEATURE_WALL_BEARINGS:
        ahead = wall_ahead(scan, float(bearing))
        if ahead is None or ahead[0] - CROSS_SHORT < min_reach:
            continue
        clear, hit = ahead
        if wall_width(scan, hit) >= min_width:
            yield float(bearing), clear, clear - CROSS_SHORT, hit
