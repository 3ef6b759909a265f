"""Random robot paths through a storey's free space, for synthetic logs on real site folders.

The occupancy grid of a ``bim-extract`` OUTDIR (``map_<storey>.pgm``) is reduced to a coarse grid
of cells with at least ``clearance`` metres to the nearest obstacle; a shortest path (Dijkstra,
cost favouring the middle of corridors) joins a random start to a random goal ``min_length`` to
``max_length`` metres away along the way. The result is a list of waypoints for
:func:`initcli.sim.synthetic_log.path_from_waypoints`.
"""

from __future__ import annotations

import math

import numpy as np

from bimtools.site.records import OccupancyGrid
from initcli.core.geometry.raster import distance_to_outside
from initcli.core.navigation.shortest_paths import csr_from_edges, dijkstra

__all__ = ["random_path"]


def _coarse_clearance(grid: OccupancyGrid, cell: float) -> tuple[np.ndarray, float, np.ndarray]:
    free = grid.occupancy() == 0
    clearance = distance_to_outside(free) * grid.resolution
    step = max(1, int(round(cell / grid.resolution)))
    rows, cols = clearance.shape[0] // step, clearance.shape[1] // step
    blocks = clearance[: rows * step, : cols * step].reshape(rows, step, cols, step)
    coarse = blocks.min(axis=(1, 3))
    return coarse, step * grid.resolution, np.array([rows, cols])


def random_path(
    grid: OccupancyGrid,
    rng: np.random.Generator,
    min_length: float = 10.0,
    max_length: float = 30.0,
    clearance: float = 0.6,
    cell: float = 0.25,
    tries: int = 50,
    near: np.ndarray | None = None,
) -> list[tuple[float, float]]:
    """Waypoints of a random collision-free path; raises ValueError if none is found.

    ``near`` (K, 2): if given, the start is the free cell nearest to one of these points chosen at
    random (e.g. 1 m in front of a feature, to start in the circulation area).
    """
    coarse, size, (rows, cols) = _coarse_clearance(grid, cell)
    ok = coarse >= clearance
    index = -np.ones(coarse.shape, dtype=np.int64)
    cells = np.argwhere(ok)
    if len(cells) < 2:
        raise ValueError("no free space with the requested clearance")
    index[ok] = np.arange(len(cells))
    src, dst, w = [], [], []
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
        a = cells
        b = cells + [dr, dc]
        inside = (b[:, 0] < rows) & (b[:, 1] >= 0) & (b[:, 1] < cols)
        a, b = a[inside], b[inside]
        j = index[b[:, 0], b[:, 1]]
        keep = j >= 0
        a, j = a[keep], j[keep]
        i = index[a[:, 0], a[:, 1]]
        length = size * math.hypot(dr, dc)
        # prefer the middle of corridors: cost grows as clearance shrinks
        cost = length * (
            1.0 + 1.0 / np.minimum(coarse[a[:, 0], a[:, 1]], coarse[b[keep][:, 0], b[keep][:, 1]])
        )
        src.append(i)
        dst.append(j)
        w.append(cost)
    graph = csr_from_edges(
        len(cells), np.concatenate(src), np.concatenate(dst), np.concatenate(w), undirected=True
    )

    def centre(k: int) -> tuple[float, float]:
        r, c = cells[k]
        x = grid.origin[0] + (c + 0.5) * size
        y = grid.origin[1] + (grid.cells.shape[0] * grid.resolution) - (r + 0.5) * size
        return float(x), float(y)

    centres = np.array([centre(k) for k in range(len(cells))])
    for _ in range(tries):
        if near is not None and len(near):
            target = np.asarray(near, dtype=float).reshape(-1, 2)[int(rng.integers(len(near)))]
            start = int(np.argmin(np.hypot(*(centres - target).T)))
        else:
            start = int(rng.integers(len(cells)))
        dist, pred = dijkstra(graph, start)
        # geometric length along the path is below the weighted cost; pick goals by weighted cost range
        reachable = np.flatnonzero(
            np.isfinite(dist) & (dist >= min_length * 1.5) & (dist <= max_length * 2.5)
        )
        if len(reachable) == 0:
            continue
        goal = int(rng.choice(reachable))
        chain = [goal]
        while chain[-1] != start:
            chain.append(int(pred[chain[-1]]))
        pts = np.array([centre(k) for k in reversed(chain)])
        length = float(np.sum(np.hypot(*np.diff(pts, axis=0).T)))
        if not (min_length <= length <= max_length):
            continue
        return _simplify(pts, size)
    raise ValueError("no path of the requested length found")


def _simplify(pts: np.ndarray, tolerance: float) -> list[tuple[float, float]]:
    """Douglas-Peucker simplification of a polyline."""
    keep = np.zeros(len(pts), dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, len(pts) - 1)]
    while stack:
        a, b = stack.pop()
        if b <= a + 1:
            continue
        seg = pts[b] - pts[a]
        norm = math.hypot(*seg) or 1.0
        d = np.abs(seg[0] * (pts[a + 1 : b, 1] - pts[a, 1]) - seg[1] * (pts[a + 1 : b, 0] - pts[a, 0])) / norm
        k = int(np.argmax(d))
        if d[k] > tolerance:
            m = a + 1 + k
            keep[m] = True
            stack.extend([(a, m), (m, b)])
    return [(float(x), float(y)) for x, y in pts[keep]]
