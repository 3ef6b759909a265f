"""Frontier exploration on a local grid built from the lidar (beyond the paper's §3.3.4).

The paper explores by following a wall, which works in corridors. In an open-plan office, a hall or a
restaurant no wall is within reach and a wall follower circles; in a room it circles the room. A
frontier explorer (Yamauchi 1997) leaves such places: every scan is integrated into a log-odds grid in
the odometry frame (free along each beam, occupied at its end point), the *frontiers* are free cells
next to unknown ones, in free space three cells across or more (a beam through a glass pane clears a
line of cells, no way on), and the robot drives to the nearest large frontier cluster along the
grid's free cells (Dijkstra on :class:`~initcli.core.navigation.grid_planner.PlanningGrid`). Frontiers that
were targeted and not reached are not chosen again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from initcli.core.geometry.jit import compiled
from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.grid_planner import PlanningGrid

__all__ = [
    "FREE_BELOW",
    "Frontier",
    "FrontierParams",
    "L_CLAMP",
    "L_FREE",
    "L_OCC",
    "LocalMap",
    "OCC_ABOVE",
]

L_FREE = -0.4  # log-odds added to a cell a beam passed through
L_OCC = 0.85  # log-odds added at a beam's end point
L_CLAMP = 4.0  # log-odds saturate at +-this
FREE_BELOW = -0.3  # a cell is known free below this log-odds (one pass of a beam) ...
OCC_ABOVE = 0.5  # ... and occupied above this (one end point)


@dataclass(frozen=True)
class FrontierParams:
    resolution: float = 0.2  # m per local-grid cell
    half_size: float = 80.0  # m: the grid spans +-this around the odometry origin
    integrate_range: float = 8.0  # m of each beam written into the grid
    min_cluster: int = 6  # cells: smaller frontier clusters are noise
    clearance: float = 0.35  # m: planning keeps this far from occupied and unknown cells (radius + 5 cm)
    size_weight: float = 0.05  # m of path traded for one frontier cell (prefers big openings)
    visited_radius: float = 1.5  # m: a frontier this close to a failed target is not chosen again


@dataclass
class Frontier:
    """A cluster of frontier cells: its centre (odom frame) and size in cells."""

    centre: np.ndarray
    size: int


@dataclass
class LocalMap:
    """A log-odds occupancy grid in the odometry frame, row 0 = lowest y."""

    params: FrontierParams = field(default_factory=FrontierParams)

    def __post_init__(self) -> None:
        n = int(round(2 * self.params.half_size / self.params.resolution))
        self.logodds = np.zeros((n, n), dtype=np.float32)
        self.origin = (-self.params.half_size, -self.params.half_size)
        self._stamp = np.zeros(n * n, dtype=np.int64)  # 2k - 1 / 2k: end point / passed in scan k
        self._scans = 0
        self.failed: list[np.ndarray] = []

    def cells_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        res = self.params.resolution
        c = np.floor((xy[:, 0] - self.origin[0]) / res).astype(np.int64)
        r = np.floor((xy[:, 1] - self.origin[1]) / res).astype(np.int64)
        return r, c

    def integrate(self, pose: Pose2D, angles: np.ndarray, ranges: np.ndarray, range_max: float) -> None:
        """Write one scan taken at ``pose`` (odom frame) into the grid: each cell a beam passed
        through (samples every 0.7 cells up to the beam's end or ``integrate_range``) gains
        ``L_FREE`` once, each cell holding an end point ``L_OCC`` once (and no ``L_FREE``). A beam
        with no return (at ``range_max``: a dropout, a black or glazed surface) clears nothing beyond
        the first cell already known occupied: it did not see through that wall."""
        p = self.params
        ranges = np.asarray(ranges, dtype=float)
        ok = np.isfinite(ranges) & (ranges > 0.05)
        if not ok.any():
            return
        a = pose.yaw + np.asarray(angles, dtype=float)[ok]
        r = ranges[ok]
        self._scans += 1
        _integrate_scan(
            self.logodds.reshape(-1), self.logodds.shape[0], self._stamp, 2 * self._scans,
            float(pose.x), float(pose.y), np.cos(a), np.sin(a), r,
            r < min(range_max, p.integrate_range), r >= range_max, np.minimum(r, p.integrate_range),
            np.arange(0.0, p.integrate_range, p.resolution * 0.7),
            float(self.origin[0]), float(self.origin[1]), float(p.resolution),
        )  # fmt: skip

    def occupancy(self) -> tuple[OccupancyGrid, tuple[int, int]]:
        """The known part of the grid as a trinary map (cropped to what was seen, 2 m margin), and the
        (row, col) offset of the crop in the full grid."""
        known = (self.logodds < FREE_BELOW) | (self.logodds > OCC_ABOVE)
        rows, cols = np.nonzero(known)
        n = self.logodds.shape[0]
        if len(rows) == 0:
            r0 = c0 = n // 2 - 1
            r1 = c1 = n // 2 + 1
        else:
            m = int(round(2.0 / self.params.resolution))
            r0, r1 = max(int(rows.min()) - m, 0), min(int(rows.max()) + m + 1, n)
            c0, c1 = max(int(cols.min()) - m, 0), min(int(cols.max()) + m + 1, n)
        lo = self.logodds[r0:r1, c0:c1]
        cells = np.full(lo.shape, UNKNOWN, dtype=np.uint8)
        cells[lo < FREE_BELOW] = FREE
        cells[lo > OCC_ABOVE] = OCCUPIED
        res = self.params.resolution
        origin = (self.origin[0] + c0 * res, self.origin[1] + r0 * res, 0.0)
        return OccupancyGrid(np.flipud(cells).copy(), res, origin), (r0, c0)

    def free_area(self) -> float:
        """m² of the cells the lidar has seen free (the space the robot explored)."""
        return float((self.logodds < FREE_BELOW).sum()) * self.params.resolution**2

    def frontiers(self) -> list[Frontier]:
        """Clusters of free cells that border unknown cells (4-neighbourhood), in free space at least
        three cells across (a way the robot could go on)."""
        grid, _ = self.occupancy()
        cells = np.flipud(grid.cells)  # row 0 = lowest y again
        # Free space narrower than three cells is no way on: a beam through a glass pane or past a
        # door leaf's edge clears a line of cells into the room behind a wall (a morphological opening).
        square = np.ones((3, 3), np.uint8)
        free = cv2.morphologyEx((cells == FREE).astype(np.uint8), cv2.MORPH_OPEN, square) > 0
        # Unknown cells right beside a wall are gaps between sparse beam end points, not openings.
        walls = cv2.dilate((cells == OCCUPIED).astype(np.uint8), square) > 0
        unknown = (cells == UNKNOWN) & ~walls
        cross = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], np.uint8)
        near_unknown = cv2.dilate(unknown.astype(np.uint8), cross)
        edge = (free & (near_unknown > 0)).astype(np.uint8)
        count, labels, stats, centroids = cv2.connectedComponentsWithStats(edge, connectivity=8)
        res = grid.resolution
        out = []
        for k in range(1, count):
            size = int(stats[k, cv2.CC_STAT_AREA])
            if size < self.params.min_cluster:
                continue
            rows, cols = np.nonzero(labels == k)
            # The member cell nearest the centroid: a free cell the planner can reach.
            cy, cx = float(centroids[k][1]), float(centroids[k][0])
            i = int(np.argmin((rows - cy) ** 2 + (cols - cx) ** 2))
            centre = np.array(
                [grid.origin[0] + (cols[i] + 0.5) * res, grid.origin[1] + (rows[i] + 0.5) * res]
            )
            out.append(Frontier(centre, size))
        return out

    def plan(
        self, pose: Pose2D, clearance: float | None = None, spacing: float = 1.5, prefer: float = 0.0
    ) -> list[np.ndarray]:
        """Waypoints (odom frame, every ``spacing`` m) to the best frontier: shortest path minus
        ``size_weight`` per cell, not near a failed target, keeping ``clearance`` (default
        ``params.clearance``) from what is not known free; ``prefer`` > 0: steps closer than that to it
        cost more (:meth:`PlanningGrid.of`: through the middle of a doorway, not across its jamb's
        corner). Empty when no frontier is reachable (the place is explored)."""
        p = self.params
        frontiers = [
            f
            for f in self.frontiers()
            if not any(float(np.hypot(*(f.centre - q))) < p.visited_radius for q in self.failed)
        ]
        if not frontiers:
            return []
        grid, _ = self.occupancy()
        # Unknown space is not free for the planner: paths run through what the lidar has seen.
        planner = PlanningGrid.of(
            grid, p.clearance if clearance is None else clearance, cell=p.resolution, prefer=prefer
        )
        if len(planner.nodes) == 0:
            return []
        dist, pred, start = planner.distances_from(pose.x, pose.y)
        if start < 0:
            return []
        best: tuple[float, int] | None = None
        for f in frontiers:
            node = planner.node_at(
                float(f.centre[0]), float(f.centre[1]), search=int(math.ceil(1.0 / p.resolution))
            )
            if node < 0 or not math.isfinite(float(dist[node])):
                continue
            if float(dist[node]) < 1.0:
                continue  # standing on it already
            score = float(dist[node]) - p.size_weight * f.size
            if best is None or score < best[0]:
                best = (score, node)
        if best is None:
            return []
        return planner.path(pred, start, best[1], spacing=spacing)

    def give_up(self, target: np.ndarray) -> None:
        """Remember a target that could not be reached (not chosen again)."""
        self.failed.append(np.asarray(target, dtype=float))

    def forget_failures(self) -> bool:
        """Forget the targets given up (each may be tried again); True when there were any."""
        had = bool(self.failed)
        self.failed.clear()
        return had


@compiled
def _integrate_scan(
    flat: np.ndarray,
    n: int,
    stamp: np.ndarray,
    mark: int,
    x: float,
    y: float,
    cos: np.ndarray,
    sin: np.ndarray,
    ranges: np.ndarray,
    hit: np.ndarray,
    lost: np.ndarray,
    reach: np.ndarray,
    steps: np.ndarray,
    x0: float,
    y0: float,
    resolution: float,
) -> None:
    """:meth:`LocalMap.integrate`'s updates of the flat float32 log-odds (row-major, ``n`` x ``n``):
    the end points of the beams that ``hit`` first (``stamp`` = mark - 1), then the cells at
    ``steps`` along each beam short of its ``reach`` that hold no end point (``stamp`` = mark),
    each cell once. A ``lost`` beam (no return) stops at the first cell known occupied; the lost
    beams pass before the others, so what they stop at is the map after the end points (they free
    no occupied cell) and the result does not depend on the beams' order."""
    occ, free, clamp = np.float32(L_OCC), np.float32(L_FREE), np.float32(L_CLAMP)
    for i in range(len(ranges)):
        if hit[i]:
            c = int(math.floor((x + ranges[i] * cos[i] - x0) / resolution))
            r = int(math.floor((y + ranges[i] * sin[i] - y0) / resolution))
            if 0 <= r < n and 0 <= c < n and stamp[r * n + c] != mark - 1:
                stamp[r * n + c] = mark - 1
                flat[r * n + c] = min(flat[r * n + c] + occ, clamp)
    for lost_pass in (True, False):
        for i in range(len(ranges)):
            if lost[i] != lost_pass:
                continue
            for j in range(len(steps)):
                if not steps[j] < reach[i]:
                    break
                c = int(math.floor((x + steps[j] * cos[i] - x0) / resolution))
                r = int(math.floor((y + steps[j] * sin[i] - y0) / resolution))
                if lost_pass and 0 <= r < n and 0 <= c < n and flat[r * n + c] > OCC_ABOVE:
                    break
                if 0 <= r < n and 0 <= c < n and stamp[r * n + c] < mark - 1:
                    stamp[r * n + c] = mark
                    flat[r * n + c] = max(flat[r * n + c] + free, -clamp)
