"""Self-similar storeys: a turn about a point that maps a storey's walls and features onto themselves.

Every sensor reading a robot can take on such a storey fits a pose ``p`` and its twin ``T p`` alike
(``T`` the turn): the walls a lidar scans, the doors, lifts and stairs a camera sees, the corners and
openings of the scan are the same seen from either. Algorithm 1 (Eq. 5-10) then always keeps two
hypotheses, and the lidar registration two places that fit alike; no amount of driving tells them
apart, and a claim would be a coin toss. Knowing it from the model alone, a session can fail at
once, honestly, instead of driving its whole ``limits.max_distance``.

A duplex house (two homes, one turned half round against the other) is such a storey; so is a
floor whose doors are not themselves point-symmetric only for a camera (the walls alone alike: a
lidar alone cannot tell the twins apart, a camera can).

The test (pure arrays, no file formats): the centre of any such turn is the centroid of the wall
cells (a set mapped onto itself by a turn has its centroid on the turn's centre), refined against
the cells' rounding; for each candidate angle, every wall cell turned about it must land within
``tolerance`` of a wall cell, and every feature turned (position and normal) about the features'
own centroid (exact, and within ``tolerance`` of the walls') on a feature of its kind, within
``tolerance`` and ``normal_tolerance``. The tolerance (0.1 m, two map cells) is below every
tolerance a claim is checked at (the scan fit's 0.15 m, ``matching.landmark_alpha`` 0.15 m, Eq. 7's
alpha 0.8 m), so a storey alike to within it has twins no check of this package can tell apart; a
wall or feature on one side only that is larger than that keeps the storey out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.nearest import PointGrid
from initcli.core.geometry.se2 import Pose2D, rot2, wrap_angle

__all__ = ["TURN_ANGLES_DEG", "Turn", "self_similar_turn"]

# Candidate turns (degrees): a storey the same after a turn of 360/n degrees is the same after any
# multiple of it, so 180 covers every even n (2, 4, 6, 8-fold) and 120 the odd one a plan has (3).
TURN_ANGLES_DEG = (180.0, 120.0)
TOLERANCE = 0.1  # m: walls and features this close after the turn are alike (two 0.05 m map cells)
NORMAL_TOLERANCE = math.radians(15.0)  # a feature's turned normal this close to its twin's
PRECHECK = 256  # wall cells tried first: most angles fail on them, without the whole query
BUCKET = 1.02  # the wall cells' bucket grid: buckets a little over a tolerance (a query looks at 3 x 3)


@dataclass(frozen=True)
class Turn:
    """A turn that maps a storey onto itself: ``angle`` (rad) about ``centre`` (x, y m)."""

    angle: float
    centre: tuple[float, float]
    tolerance: float  # m: how alike (walls and features)

    @property
    def degrees(self) -> float:
        return math.degrees(self.angle)

    def twin(self, x: float, y: float, yaw: float) -> tuple[float, float, float]:
        """The pose every reading fits as well as (x, y, yaw)."""
        return (_turn(self.angle, self.centre) * Pose2D(x, y, yaw)).as_tuple()


def self_similar_turn(
    walls: np.ndarray,
    features: np.ndarray,
    normals: np.ndarray,
    kinds: np.ndarray,
    tolerance: float = TOLERANCE,
    normal_tolerance: float = NORMAL_TOLERANCE,
) -> Turn | None:
    """The first turn of :data:`TURN_ANGLES_DEG` that maps the storey onto itself, or None.

    ``walls`` (N, 2): the centres of the occupied map cells (m); ``features`` (M, 2) and ``normals``
    (M, 2, unit): each feature's position and the normal it is seen along; ``kinds`` (M,): its
    category (any comparable labels). A storey with no walls is never self-similar here.
    """
    walls = np.asarray(walls, dtype=float).reshape(-1, 2)
    xy = np.asarray(features, dtype=float).reshape(-1, 2)
    if len(walls) < 3:
        return None
    centre = (float(walls[:, 0].mean()), float(walls[:, 1].mean()))
    grid = PointGrid(walls, cell=BUCKET * tolerance)
    rng = np.random.default_rng(0)
    sample = walls[rng.choice(len(walls), size=min(PRECHECK, len(walls)), replace=False)]
    for degrees in TURN_ANGLES_DEG:
        angle = math.radians(degrees)
        if not _lands_on(grid, _turn(angle, centre).apply(sample), tolerance):
            continue
        if not _lands_on(grid, _turn(angle, centre).apply(walls), tolerance):
            continue
        # the cells' centroid is off the true centre by a fraction of a cell: refine it on the walls
        at = _refined_centre(grid, walls, angle, centre)
        if not _lands_on(grid, _turn(angle, at).apply(walls), tolerance):
            at = centre
        # The features' own centroid is the centre of any turn that maps them onto themselves, exact
        # where the map's cells are off by a fraction of one: test them about it, near the walls'.
        if len(xy):
            own = (float(xy[:, 0].mean()), float(xy[:, 1].mean()))
            if math.dist(own, at) > tolerance:
                continue
            at = own
        if _features_alike(xy, normals, kinds, angle, at, tolerance, normal_tolerance):
            return Turn(angle, at, tolerance)
    return None


def _refined_centre(
    grid: PointGrid, walls: np.ndarray, angle: float, centre: tuple[float, float], rounds: int = 3
) -> tuple[float, float]:
    """The centre that brings the turned walls closest to the walls: each round moves it by the
    least-squares step for the mean offset to the nearest wall cells. A turn about ``c`` maps ``p``
    to ``R p + (I - R) c``, so an offset ``r`` of the turned points is undone by ``(I - R)^-1 r``."""
    step = np.linalg.inv(np.eye(2) - rot2(angle))
    at = np.asarray(centre, dtype=float)
    for _ in range(rounds):
        moved = _turn(angle, (float(at[0]), float(at[1]))).apply(walls)
        _, nearest = grid.nearest(moved)
        at = at + step @ (walls[nearest] - moved).mean(axis=0)
    return float(at[0]), float(at[1])


def _turn(angle: float, centre: tuple[float, float]) -> Pose2D:
    """The turn by ``angle`` about ``centre`` as a rigid transform (Eq. 11): ``R p + (I - R) c``."""
    x, y = np.asarray(centre) - rot2(angle) @ np.asarray(centre)
    return Pose2D(float(x), float(y), angle)


def _lands_on(grid: PointGrid, points: np.ndarray, tolerance: float) -> bool:
    """Does every point lie within ``tolerance`` of one of the grid's points?"""
    distance, _ = grid.nearest(points, upper_bound=tolerance + 1e-9)
    return bool(np.all(np.isfinite(distance)))


def _features_alike(
    features: np.ndarray,
    normals: np.ndarray,
    kinds: np.ndarray,
    angle: float,
    centre: tuple[float, float],
    tolerance: float,
    normal_tolerance: float,
) -> bool:
    """Does every feature (``features`` (M, 2)), turned, land on one of its kind facing the same way?"""
    if len(features) == 0:
        return True
    n = np.asarray(normals, dtype=float).reshape(-1, 2)
    labels = np.asarray(kinds)
    moved = _turn(angle, centre).apply(features)
    heading = np.arctan2(n[:, 1], n[:, 0])
    for i in range(len(features)):
        near = np.hypot(*(features - moved[i]).T) <= tolerance
        same = labels == labels[i]
        facing = np.abs(wrap_angle(heading - heading[i] - angle))
        if not np.any(near & same & (facing <= normal_tolerance)):
            return False
    return True
