"""Spaces a lidar cannot tell apart: a free region of the map that a rigid motion lays onto itself or
onto another region, walls on walls and free cells on free cells.

A robot whose camera sees nothing has only its scans: from inside a region closed off by its
doors (every leaf shut) it can see the region's walls and nothing beyond them. When a turn or a
shift maps the region's walls onto the map's walls and its floor onto free floor, every scan taken
at a pose ``p`` there is the scan taken at the twin pose ``T p``: no registration, scan fit or
amount of driving tells the two apart, and a lidar-only claim would be a coin toss. Two identical
offices along a corridor are twins (a shift), a ring corridor whose plan is point-symmetric once
its doors are shut is its own twin (a half turn), although the rooms behind the doors differ and
the storey as a whole (:mod:`initcli.core.lidar.symmetry`) is not self-similar. An open door, a camera
feature or anything on site the model lacks (material, hoardings) can break the tie.

The test (pure arrays): each region's candidate motions come from its free cells' moments (the
centroid of the region onto that of a region of about the same area, turned by the difference of
their principal axes and by the quarter turns of the map's grid, each plus multiples of a quarter
turn; a 5-degree sweep where a region is too round for its axis to mean anything; never the
identity), refined on a small grid; a motion counts when every wall cell bordering the region lands
within ``tolerance`` of a wall cell that borders free space, every wall cell bordering the twin
lands back within ``tolerance`` of one (a column by one wall of the twin only), and every free cell
beyond the tolerance from a wall lands on a free cell. The map's edge counts as wall. A mirror
image is no twin (a lidar sees handedness).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from initcli.core.geometry.nearest import PointGrid
from initcli.core.geometry.raster import distance_to_outside
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.lidar.symmetry import TOLERANCE

__all__ = ["IDENTITY_M", "RegionTwin", "moved", "region_twins"]

AREA_SLACK = 0.05  # share of a region's free cells another region's count may differ by to be tried
WALL_SLACK = 0.1  # share of its bordering wall cells likewise
REFINE_CELLS = (-1.0, -0.5, 0.0, 0.5, 1.0)  # shifts (cells) of the refinement grid, in x and y
REFINE_DEG = (-1.0, -0.5, 0.0, 0.5, 1.0)  # turns (degrees) of the refinement grid
SAMPLE = 256  # wall cells the refinement is scored on; the best motion is then checked on all
IDENTITY_M = 1.0  # m: a motion that moves no wall cell of the region further than this is no twin
ROUND = 0.1  # a region whose second moments differ by less than this share has no principal axis
SWEEP_DEG = 5.0  # degrees between the turns tried on such a region
BUCKET = 0.51  # the wall cells' bucket grid: buckets a little over half a tolerance (a query looks at 5 x 5)


@dataclass(frozen=True)
class RegionTwin:
    """A region (``label`` of the labelled free cells) and the rigid motion (BIM frame) that lays it on
    ``twin`` (its own label: the region turned onto itself)."""

    label: int
    twin: int
    motion: Pose2D  # p -> R p + t, metres and radians

    @property
    def turn_deg(self) -> float:
        """The turn in degrees, in (-180, 180] (a half turn is 180, a shift 0, never -0)."""
        deg = math.degrees(wrap_angle(self.motion.yaw))
        return 180.0 if deg <= -179.95 else deg + 0.0


def region_twins(
    labels: np.ndarray,
    resolution: float,
    origin: tuple[float, float],
    regions: list[int] | np.ndarray,
    tolerance: float = TOLERANCE,
) -> list[RegionTwin]:
    """The twins of the ``regions`` (labels) of ``labels`` (H, W; 0: not free, else the connected free
    region; row 0 the top, ``origin`` the bottom-left corner in metres, ``resolution`` m per cell):
    for each region that has one, the first motion found. Regions have no twin where none is listed."""
    # one cell of wall round the map: its edge bounds what a lidar sees, as a wall does
    labels = np.pad(np.asarray(labels, dtype=np.int64), 1)
    origin = (origin[0] - resolution, origin[1] - resolution)
    free = labels > 0
    walls = ~free & _dilated(free)
    wall_xy = _xy(np.nonzero(walls), labels.shape, resolution, origin)
    if len(wall_xy) < 3:
        return []
    grid = PointGrid(wall_xy, cell=BUCKET * tolerance)
    near = _Lookup(distance_to_outside(~walls) * resolution, resolution, origin)
    beyond = distance_to_outside(free) * resolution >= tolerance + 1.5 * resolution
    counts = np.bincount(labels.ravel(), minlength=int(labels.max()) + 1)
    shape = _Shapes(labels, walls, beyond, resolution, origin)
    out: list[RegionTwin] = []
    wanted = list(dict.fromkeys(int(r) for r in regions if 0 < int(r) < len(counts) and counts[int(r)] > 0))
    for label in wanted:
        n_walls = len(shape.walls(label))
        similar = [
            other
            for other in range(1, len(counts))
            if abs(int(counts[other]) - int(counts[label])) <= AREA_SLACK * counts[label]
            and abs(len(shape.walls(other)) - n_walls) <= WALL_SLACK * n_walls
        ]
        for other in [label, *(o for o in similar if o != label)]:
            motion = _fit(shape, grid, near, labels, label, other, tolerance)
            if motion is not None:
                out.append(RegionTwin(label, other, motion))
                break
    return out


class _Shapes:
    """Per region, computed once on its bounding box: its bordering wall cells, its free cells beyond
    the tolerance from a wall, its centroid and principal axis (metres, radians)."""

    def __init__(
        self,
        labels: np.ndarray,
        walls: np.ndarray,
        beyond: np.ndarray,
        resolution: float,
        origin: tuple[float, float],
    ) -> None:
        self.labels, self.walls_mask, self.beyond = labels, walls, beyond
        self.resolution, self.origin = resolution, origin
        self.boxes = _boxes(labels)
        self._walls: dict[int, np.ndarray] = {}
        self._inner: dict[int, np.ndarray] = {}
        self._axes: dict[int, tuple[np.ndarray, float | None]] = {}

    def _box(self, label: int, pad: int) -> tuple[slice, slice]:
        box = self.boxes[label - 1]
        assert box is not None  # a region tried has cells
        rows, cols = box
        h, w = self.labels.shape
        return (
            slice(max(0, rows.start - pad), min(h, rows.stop + pad)),
            slice(max(0, cols.start - pad), min(w, cols.stop + pad)),
        )

    def _cells(self, mask: np.ndarray, box: tuple[slice, slice]) -> np.ndarray:
        rows, cols = np.nonzero(mask)
        return _xy(
            (rows + box[0].start, cols + box[1].start), self.labels.shape, self.resolution, self.origin
        )

    def walls(self, label: int) -> np.ndarray:
        if label not in self._walls:
            box = self._box(label, 2)
            near = _dilated(self.labels[box] == label)
            self._walls[label] = self._cells(near & self.walls_mask[box], box)
        return self._walls[label]

    def inner(self, label: int) -> np.ndarray:
        if label not in self._inner:
            box = self._box(label, 0)
            self._inner[label] = self._cells((self.labels[box] == label) & self.beyond[box], box)
        return self._inner[label]

    def axis(self, label: int) -> tuple[np.ndarray, float | None]:
        """The centroid of the region's free cells and its principal axis (moments; None: the
        region is too round for one)."""
        if label not in self._axes:
            box = self._box(label, 0)
            xy = self._cells(self.labels[box] == label, box)
            c = xy.mean(axis=0)
            d = xy - c
            mu20, mu02, mu11 = (
                float((d[:, 0] ** 2).mean()),
                float((d[:, 1] ** 2).mean()),
                float((d[:, 0] * d[:, 1]).mean()),
            )
            round_ = math.hypot(mu20 - mu02, 2 * mu11) < ROUND * (mu20 + mu02)
            self._axes[label] = (c, None if round_ else 0.5 * math.atan2(2 * mu11, mu20 - mu02))
        return self._axes[label]


def _fit(
    shape: _Shapes,
    grid: PointGrid,
    near: _Lookup,
    labels: np.ndarray,
    label: int,
    other: int,
    tolerance: float,
) -> Pose2D | None:
    """The motion laying region ``label`` on region ``other``, or None."""
    walls, back = shape.walls(label), shape.walls(other)
    sample = walls[:: max(1, len(walls) // SAMPLE)]
    inner = shape.inner(label)
    (c, theta), (c2, theta2) = shape.axis(label), shape.axis(other)
    for angle0 in _angles(theta, theta2):
        if other == label and abs(wrap_angle(angle0)) < math.radians(SWEEP_DEG):
            continue  # the identity
        motions, placed = _refined(near, sample, c, c2, angle0, shape.resolution, tolerance)
        if not motions:
            continue
        # the motion whose sampled wall cells lie closest (the first of equals): one query for all
        worst = grid.nearest(placed, upper_bound=tolerance + 1e-9)[0].reshape(len(motions), -1).max(axis=1)
        motion = motions[int(np.argmin(worst))]
        if _worst(grid, motion.apply(walls), tolerance) > tolerance:
            continue
        if _worst(grid, motion.inverse().apply(back), tolerance) > tolerance:
            continue
        if other == label and moved(motion, walls).max(initial=0.0) < IDENTITY_M:
            continue
        if _on_free(motion.apply(inner), labels, shape.resolution, shape.origin):
            return motion
    return None


def _angles(theta: float | None, theta2: float | None) -> list[float]:
    """The turns tried (radians): the difference of the principal axes and the grid's own, each
    with its quarter turns; every SWEEP_DEG degrees where either region is too round for an axis."""
    if theta is None or theta2 is None:
        return [math.radians(d) for d in np.arange(0.0, 360.0, SWEEP_DEG)]
    bases = [theta2 - theta, 0.0]
    angles = [wrap_angle(b + q * math.pi / 2) for b in bases for q in range(4)]
    out: list[float] = []
    for a in angles:  # the axes' difference first; the grid's turns where they differ from it
        if all(abs(wrap_angle(a - b)) > math.radians(2.0) for b in out):
            out.append(float(a))
    return out


def _refined(
    near: _Lookup,
    sample: np.ndarray,
    centroid: np.ndarray,
    target: np.ndarray,
    angle0: float,
    resolution: float,
    tolerance: float,
) -> tuple[list[Pose2D], np.ndarray]:
    """The motions of the refinement grid about ``angle0`` (centroid onto target), for an exact check,
    and the sampled wall cells each lays (motion by motion), or none when the distance map shows
    that none lays every sampled wall cell within ``tolerance`` (and the map's rounding) of a wall.
    The unrefined motion is tried first: a region it lays far off (median beyond three tolerances)
    has no twin at this angle."""
    shift = target - Pose2D(0.0, 0.0, angle0).apply(centroid)
    base = Pose2D(float(shift[0]), float(shift[1]), angle0)
    if float(np.median(near(base.apply(sample)))) > 3 * tolerance:
        return [], sample[:0]
    motions = []
    for ddeg in REFINE_DEG:
        angle = angle0 + math.radians(ddeg)
        shift = target - Pose2D(0.0, 0.0, angle).apply(centroid)
        motions += [
            Pose2D(float(shift[0] + dx * resolution), float(shift[1] + dy * resolution), angle)
            for dx in REFINE_CELLS
            for dy in REFINE_CELLS
        ]
    moved = np.concatenate([m.apply(sample) for m in motions])
    worst = near(moved).reshape(len(motions), -1).max(axis=1)
    if worst.min() > tolerance + near.slack:
        return [], sample[:0]
    return motions, moved


class _Lookup:
    """The distance (m) from a point to the nearest wall cell, read off a distance map of the cells
    (off by at most ``slack``, half a cell's diagonal; points off the map: infinite)."""

    def __init__(self, distance: np.ndarray, resolution: float, origin: tuple[float, float]) -> None:
        self.distance, self.resolution, self.origin = distance, resolution, origin
        self.slack = resolution * math.sqrt(0.5)

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        row, col, inside = _cells_of(xy, self.distance.shape, self.resolution, self.origin)
        out = np.full(len(xy), np.inf)
        out[inside] = self.distance[row[inside], col[inside]]
        return out


def _worst(grid: PointGrid, xy: np.ndarray, tolerance: float) -> float:
    """The largest distance from a point to the nearest wall cell (inf: one beyond ``tolerance``)."""
    return float(grid.nearest(xy, upper_bound=tolerance + 1e-9)[0].max())


def moved(motion: Pose2D, xy: np.ndarray) -> np.ndarray:
    """(N,) m: how far ``motion`` moves each of the points ``xy`` (N, 2)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    return np.asarray(np.hypot(*(motion.apply(xy) - xy).T))


def _on_free(xy: np.ndarray, labels: np.ndarray, resolution: float, origin: tuple[float, float]) -> bool:
    """Does every point lie on a free cell of ``labels``? (No points: nothing to say, no.)"""
    if not len(xy):
        return False
    row, col, inside = _cells_of(xy, labels.shape, resolution, origin)
    return bool(inside.all() and (labels[row, col] > 0).all())


def _cells_of(
    xy: np.ndarray, shape: tuple[int, ...], resolution: float, origin: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The (row, col) of the cells holding the points ``xy`` (N, 2) m, row 0 the top, and which lie
    on the map (the inverse of :func:`_xy`)."""
    col = np.floor((xy[:, 0] - origin[0]) / resolution).astype(int)
    row = shape[0] - 1 - np.floor((xy[:, 1] - origin[1]) / resolution).astype(int)
    inside = (row >= 0) & (row < shape[0]) & (col >= 0) & (col < shape[1])
    return row, col, inside


def _xy(
    cells: tuple[np.ndarray, ...], shape: tuple[int, ...], resolution: float, origin: tuple[float, float]
) -> np.ndarray:
    """Cell centres (rows, cols) as (N, 2) metres, row 0 the top."""
    rows, cols = cells
    x = origin[0] + (cols + 0.5) * resolution
    y = origin[1] + (shape[0] - 1 - rows + 0.5) * resolution
    return np.column_stack([x, y]).astype(float).reshape(-1, 2)


def _dilated(mask: np.ndarray) -> np.ndarray:
    """``mask`` (bool) grown by one cell, diagonals included (3 x 3); nothing beyond the edge."""
    grown = cv2.dilate(
        mask.astype(np.uint8), np.ones((3, 3), dtype=np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=0
    )
    return np.asarray(grown > 0)


def _boxes(labels: np.ndarray) -> list[tuple[slice, slice] | None]:
    """Per label 1..max of ``labels`` (H, W), the (rows, cols) slices of its bounding box (None: no
    cell)."""
    n = int(labels.max(initial=0))
    cells = np.flatnonzero(labels)
    label = labels.ravel()[cells]
    row, col = np.divmod(cells, labels.shape[1])
    lo_r = np.full(n + 1, labels.shape[0])
    lo_c = np.full(n + 1, labels.shape[1])
    hi_r = np.full(n + 1, -1)
    hi_c = np.full(n + 1, -1)
    np.minimum.at(lo_r, label, row)
    np.minimum.at(lo_c, label, col)
    np.maximum.at(hi_r, label, row)
    np.maximum.at(hi_c, label, col)
    return [
        (slice(int(lo_r[k]), int(hi_r[k]) + 1), slice(int(lo_c[k]), int(hi_c[k]) + 1))
        if hi_r[k] >= 0
        else None
        for k in range(1, n + 1)
    ]
