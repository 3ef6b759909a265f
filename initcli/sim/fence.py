"""The site fence: where the storey's free space reaches the outside, the simulated world ends.

A building under construction is often open: gates stand open, a façade is not built yet. The map
(bim-extract) bounds its free space by the building (its walls, spaces and floor slabs), and where
that free space meets the map's unknown outside with no wall between, the simulated robot would
drive out into nothing. Along those borders the simulated world gets a thin fence (as a site's
hoarding round the building): the lidar sees it, the robot does not pass it. In a closed building
the free space meets no unknown cell but behind door openings, where the fence lies behind the
door's leaf.
"""

from __future__ import annotations

import numpy as np

from bimtools.site.records import FREE, UNKNOWN, Obstacle, OccupancyGrid

__all__ = ["FENCE_CLASS", "FENCE_THICKNESS", "open_borders", "site_fence"]

FENCE_CLASS = "SiteFence"
FENCE_THICKNESS = 0.02  # m, on the outside of the border


def _runs(mask: np.ndarray) -> list[tuple[int, int, int]]:
    """(line, first, last) of each run of True along axis 1 of a 2-D mask."""
    out: list[tuple[int, int, int]] = []
    padded = np.pad(mask.astype(np.int8), ((0, 0), (1, 1)))
    edges = np.diff(padded, axis=1)
    for line in np.flatnonzero(mask.any(axis=1)):
        starts = np.flatnonzero(edges[line] == 1)
        ends = np.flatnonzero(edges[line] == -1) - 1
        out += [(int(line), int(a), int(b)) for a, b in zip(starts, ends, strict=True)]
    return out


def open_borders(grid: OccupancyGrid) -> np.ndarray:
    """(S, 6) borders where a free cell meets an unknown one (4-neighbours): x1, y1, x2, y2 and the
    unit normal toward the unknown side, merged into straight runs along the grid lines."""
    cells = np.asarray(grid.cells)
    free, unknown = cells == FREE, cells == UNKNOWN
    res, (x0, y0) = grid.resolution, (grid.origin[0], grid.origin[1])
    top = y0 + cells.shape[0] * res  # the upper edge of row 0
    out: list[tuple[float, float, float, float, float, float]] = []
    # between row r and row r + 1 (row r + 1 lies below): y = top - (r + 1) res
    for mask, ny in ((free[:-1] & unknown[1:], -1.0), (unknown[:-1] & free[1:], 1.0)):
        for r, a, b in _runs(mask):
            y = top - (r + 1) * res
            out.append((x0 + a * res, y, x0 + (b + 1) * res, y, 0.0, ny))
    # between column c and column c + 1: x = x0 + (c + 1) res
    for mask, nx in ((free[:, :-1] & unknown[:, 1:], 1.0), (unknown[:, :-1] & free[:, 1:], -1.0)):
        for c, a, b in _runs(mask.T):
            x = x0 + (c + 1) * res
            out.append((x, top - a * res, x, top - (b + 1) * res, nx, 0.0))
    return np.array(out, dtype=float).reshape(-1, 6)


def site_fence(grid: OccupancyGrid | None) -> list[Obstacle]:
    """A thin obstacle along each of :func:`open_borders`, on its outside (none without a map)."""
    if grid is None:
        return []
    fence: list[Obstacle] = []
    for k, (x1, y1, x2, y2, nx, ny) in enumerate(open_borders(grid)):
        d = FENCE_THICKNESS
        ring = ((x1, y1), (x2, y2), (x2 + d * nx, y2 + d * ny), (x1 + d * nx, y1 + d * ny))
        fence.append(Obstacle("", f"fence-{k}", FENCE_CLASS, ring))
    return fence
