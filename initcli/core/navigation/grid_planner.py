"""Shortest paths on the BIM occupancy grid, for active exploration under a pose hypothesis.

The paper's modified bug algorithm needs only the target's relative position; with a hypothesis
we also know where the walls are, so the target is reached along the BIM's corridors: a path on a
coarse grid of cells with enough clearance (Dijkstra, 8-connected), thinned to waypoints that the
bug navigator follows (it still walks around unmapped obstacles).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from bimtools.site.records import FREE, OccupancyGrid
from initcli.core.navigation.shortest_paths import NO_PREDECESSOR, CsrGraph, csr_from_edges, dijkstra

__all__ = ["DOOR_SEAL_MARGIN", "PREFER_WEIGHT", "PlanningGrid", "with_doors_closed"]

DOOR_SEAL_MARGIN = 0.15  # m beyond each side of a door's width that the seal drawn across it reaches
PREFER_WEIGHT = 4.0  # a step at the least clearance costs this much more than its length (prefer)


def with_doors_closed(grid: OccupancyGrid, doors: np.ndarray) -> OccupancyGrid:
    """A copy of ``grid`` with a wall across each door opening: ``doors`` (n, 5) rows x, y, norm_x,
    norm_y, width (m). A robot cannot open doors, so routes must stay out of the rooms behind them."""
    cells = grid.cells.copy()
    thickness = max(2, int(math.ceil(0.1 / grid.resolution)))
    for x, y, nx, ny, width in np.asarray(doors, dtype=float).reshape(-1, 5):
        half = max(width, 0.6) / 2 + DOOR_SEAL_MARGIN
        ends = np.array([[x - ny * half, y + nx * half], [x + ny * half, y - nx * half]])
        row, col = grid.world_to_cell(ends[:, 0], ends[:, 1])
        cv2.line(cells, (int(col[0]), int(row[0])), (int(col[1]), int(row[1])), 0, thickness=thickness)
    return OccupancyGrid(
        cells, grid.resolution, grid.origin, grid.negate, grid.occupied_thresh, grid.free_thresh
    )


@dataclass
class PlanningGrid:
    """Free cells with clearance of a storey map, resampled to ``cell`` metres, as a graph."""

    origin: tuple[float, float]
    cell: float
    free: np.ndarray  # (rows, cols) bool, row 0 = lowest y
    graph: CsrGraph  # over the free cells (nodes), both directions of each step
    index: np.ndarray  # (rows, cols) -> node id or -1
    nodes: np.ndarray  # (n, 2) row, col of each node

    @staticmethod
    def of(grid: OccupancyGrid, clearance: float, cell: float = 0.2, prefer: float = 0.0) -> PlanningGrid:
        """``prefer`` > ``clearance``: a step between cells closer than ``prefer`` to what is not free
        costs up to 1 + PREFER_WEIGHT times its length (paths keep to the middle of a doorway)."""
        free = (grid.cells == FREE).astype(np.uint8)
        dist = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * grid.resolution
        ok = np.flipud(dist >= clearance)  # row 0 = lowest y
        step = max(1, int(round(cell / grid.resolution)))
        rows, cols = ok.shape[0] // step, ok.shape[1] // step
        coarse = ok[: rows * step, : cols * step].reshape(rows, step, cols, step).mean(axis=(1, 3)) > 0.5
        index = np.full(coarse.shape, -1, dtype=np.int64)
        nodes = np.argwhere(coarse)
        index[nodes[:, 0], nodes[:, 1]] = np.arange(len(nodes))
        src, dst, weight = [], [], []
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
            r2, c2 = nodes[:, 0] + dr, nodes[:, 1] + dc
            inside = (r2 >= 0) & (r2 < rows) & (c2 >= 0) & (c2 < cols)
            other = np.full(len(nodes), -1)
            other[inside] = index[r2[inside], c2[inside]]
            good = other >= 0
            src.append(np.flatnonzero(good))
            dst.append(other[good])
            weight.append(np.full(good.sum(), math.hypot(dr, dc) * step * grid.resolution))
        s, d, w = np.concatenate(src), np.concatenate(dst), np.concatenate(weight)
        if prefer > clearance:
            at = np.flipud(dist)[nodes[:, 0] * step + step // 2, nodes[:, 1] * step + step // 2]
            short = np.clip((prefer - at) / (prefer - clearance), 0.0, 1.0)
            w = w * (1.0 + PREFER_WEIGHT * (short[s] + short[d]) / 2)
        graph = csr_from_edges(len(nodes), s, d, w, undirected=True)
        return PlanningGrid(
            (grid.origin[0], grid.origin[1]), step * grid.resolution, coarse, graph, index, nodes
        )

    def node_at(self, x: float, y: float, search: int = 4) -> int:
        """The free node nearest to a world point (within ``search`` cells), or -1."""
        r = int(math.floor((y - self.origin[1]) / self.cell))
        c = int(math.floor((x - self.origin[0]) / self.cell))
        best, best_d = -1, math.inf
        for dr in range(-search, search + 1):
            for dc in range(-search, search + 1):
                rr, cc = r + dr, c + dc
                if (
                    0 <= rr < self.index.shape[0]
                    and 0 <= cc < self.index.shape[1]
                    and self.index[rr, cc] >= 0
                ):
                    d = dr * dr + dc * dc
                    if d < best_d:
                        best, best_d = int(self.index[rr, cc]), d
        return best

    def centre(self, node: int) -> np.ndarray:
        r, c = self.nodes[node]
        return np.array([self.origin[0] + (c + 0.5) * self.cell, self.origin[1] + (r + 0.5) * self.cell])

    def distances_from(self, x: float, y: float) -> tuple[np.ndarray, np.ndarray, int]:
        """Path lengths and predecessors from the node nearest (x, y) (inf where unreachable)."""
        start = self.node_at(x, y)
        if start < 0:
            n = len(self.nodes)
            return np.full(n, np.inf), np.full(n, NO_PREDECESSOR), -1
        dist, pred = dijkstra(self.graph, start)
        return dist, pred, start

    def path(self, pred: np.ndarray, start: int, goal: int, spacing: float = 2.0) -> list[np.ndarray]:
        """Waypoints (world) every ``spacing`` metres along the shortest path, ending at the goal."""
        if goal < 0 or start < 0:
            return []
        chain = [goal]
        while chain[-1] != start:
            prev = int(pred[chain[-1]])
            if prev < 0:
                return []
            chain.append(prev)
        points = [self.centre(n) for n in reversed(chain)]
        waypoints: list[np.ndarray] = []
        travelled = 0.0
        for a, b in zip(points[:-1], points[1:], strict=True):
            travelled += float(np.hypot(*(b - a)))
            if travelled >= spacing:
                waypoints.append(b)
                travelled = 0.0
        if not waypoints or np.hypot(*(waypoints[-1] - points[-1])) > 1e-9:
            waypoints.append(points[-1])
        return waypoints
