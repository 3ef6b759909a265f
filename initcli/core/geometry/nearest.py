"""Exact nearest-neighbour and fixed-radius queries on 2-D points: a uniform bucket grid.

:class:`PointGrid` sorts the points by the square bucket (side ``cell``) they fall in; a query looks
at the block of buckets around its own, whose rows are each one contiguous range of the sorted
points. Every answer is exact (a brute-force scan's, up to ties and float rounding) whatever the
bucket size, which only sets the speed: a query whose radius or upper bound is ``k`` cells looks at
(2k + 1) x (2k + 1) buckets. Pure numpy; queries go in chunks of a bounded number of candidate pairs.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

__all__ = ["PointGrid"]

CANDIDATES = 1 << 20  # candidate pairs held at once (one chunk of queries)
MAX_BUCKETS = 1 << 22  # buckets of the grid at most (its start table: 8 bytes each) ...
PER_POINT = 16  # ... and at most this many per point (at least 4096): a build in time linear in N
SMALL = 32  # sets of at most this many points are scanned whole (faster than the buckets) ...
SCAN = 8192  # ... and so are queries times points up to this
_MARGIN = 1e-6  # of a cell: slack for the rounding of bucket indices


class PointGrid:
    """A uniform bucket grid over ``points`` (N, 2), for exact nearest-neighbour and radius queries.

    ``cell``: the bucket side; None picks about two points per bucket over the points' bounding box.
    It is raised where the grid would exceed :data:`MAX_BUCKETS` buckets or :data:`PER_POINT` per
    point.
    """

    def __init__(self, points: np.ndarray, cell: float | None = None) -> None:
        self.points = np.asarray(points, dtype=float).reshape(-1, 2)
        if not np.isfinite(self.points).all():
            raise ValueError("points must be finite")
        n = len(self.points)
        self.lo = self.points.min(axis=0) if n else np.zeros(2)
        self.hi = self.points.max(axis=0) if n else np.zeros(2)
        span = self.hi - self.lo
        self.cell = _cell_size(span, n, cell)
        count = np.floor(span / self.cell).astype(np.intp) + 1  # the same rounding as _buckets
        self.shape = (int(count[1]), int(count[0]))  # rows (y), columns (x)
        ix, iy = self._buckets(self.points)
        key = iy * self.shape[1] + ix
        self.order = np.argsort(key, kind="stable")  # sorted position -> point index
        self.xs = np.ascontiguousarray(self.points[self.order, 0])
        self.ys = np.ascontiguousarray(self.points[self.order, 1])
        counts = np.bincount(key, minlength=self.shape[0] * self.shape[1])
        self.starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)  # bucket -> first position

    def __len__(self) -> int:
        return len(self.points)

    def nearest(self, points: np.ndarray, upper_bound: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
        """The nearest point to each query (M, 2): (distance (M,), index (M,)); distance ``inf`` and
        index N where no point lies closer than ``upper_bound`` (strictly, as ``cKDTree.query``).
        Of equidistant points, any one (the same every time)."""
        q = _queries(points)
        n = len(self)
        best = np.full(len(q), np.inf)  # squared distances
        index = np.full(len(q), n, dtype=np.intp)
        if len(q) == 0 or n == 0 or not upper_bound > 0:
            return best, index
        bound2 = upper_bound * upper_bound
        if n <= SMALL or len(q) * n <= SCAN:
            best, index = self._scan(q)
        else:
            # queries farther than the bound from the points' bounding box: nothing to look at
            gap = np.maximum(self.lo - q, 0.0) + np.maximum(q - self.hi, 0.0)
            pending = np.flatnonzero(_d2(gap, 0.0) < bound2)
            whole = max(self.shape) + 2  # a block of this many rings covers the grid
            # a block that holds the bound where it is a few cells; else growing blocks from 3 x 3
            span = upper_bound / self.cell
            ring = min(whole, math.ceil(span + _MARGIN)) if span <= 4 else 1
            while len(pending):
                reach = (ring - _MARGIN) * self.cell  # every point outside the block lies farther
                d2, idx = self._best(q[pending], ring)
                done = (d2 <= reach * reach) | (upper_bound <= reach) | (ring >= whole)
                best[pending[done]] = d2[done]
                index[pending[done]] = idx[done]
                pending = pending[~done]
                ring = min(whole, 2 * ring)
        far = ~(best < bound2)
        index[far] = n
        return np.where(far, np.inf, np.sqrt(best)), index

    def within(self, centres: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
        """Every pair (query row, point index) at distance <= ``radius``, sorted by row, then index."""
        q = _queries(centres)
        n = len(self)
        rows_out: list[np.ndarray] = [np.zeros(0, dtype=np.intp)]
        idx_out: list[np.ndarray] = [np.zeros(0, dtype=np.intp)]
        if len(q) == 0 or n == 0 or not radius >= 0:
            return rows_out[0], idx_out[0]
        r2 = radius * radius
        if n <= SMALL or len(q) * n <= SCAN:
            step = max(1, CANDIDATES // n)
            for a in range(0, len(q), step):
                row, idx = np.nonzero(_d2(q[a : a + step, None, :], self.points[None, :, :]) <= r2)
                rows_out.append(row + a)
                idx_out.append(idx)
        else:
            look = radius / self.cell
            ring = math.floor(min(look, max(self.shape)) + _MARGIN) + 1  # a block that holds the disc
            for first, count, pos in self._candidates(q, ring, look):
                hit = self._distances(q[first : first + len(count)], count, pos) <= r2
                row = np.repeat(np.arange(first, first + len(count)), count)[hit]
                idx = self.order[pos[hit]]
                sort = np.argsort(row * n + idx)
                rows_out.append(row[sort])
                idx_out.append(idx[sort])
        return np.concatenate(rows_out).astype(np.intp), np.concatenate(idx_out).astype(np.intp)

    # -- internals ---------------------------------------------------------------------------------

    def _buckets(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bucket column and row of each point (queries: clipped to two buckets beyond the grid)."""
        return self._clipped((xy - self.lo) / self.cell)

    def _clipped(self, rel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ix = np.minimum(np.maximum(np.floor(rel[:, 0]), -2), self.shape[1] + 1).astype(np.intp)
        iy = np.minimum(np.maximum(np.floor(rel[:, 1]), -2), self.shape[0] + 1).astype(np.intp)
        return ix, iy

    def _scan(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Squared distance and index of the nearest point by a scan of every point (small sets)."""
        step = max(1, CANDIDATES // len(self))
        best = np.empty(len(q))
        index = np.empty(len(q), dtype=np.intp)
        for a in range(0, len(q), step):
            d2 = _d2(q[a : a + step, None, :], self.points[None, :, :])
            k = np.argmin(d2, axis=1)
            index[a : a + step] = k
            best[a : a + step] = d2[np.arange(len(k)), k]
        return best, index

    def _distances(self, q: np.ndarray, count: np.ndarray, pos: np.ndarray) -> np.ndarray:
        """Squared distances of the candidates ``pos`` (sorted positions), ``count`` for each query."""
        d = self.xs[pos]
        d -= np.repeat(q[:, 0], count)
        d *= d
        e = self.ys[pos]
        e -= np.repeat(q[:, 1], count)
        e *= e
        d += e
        return np.asarray(d)

    def _best(self, q: np.ndarray, ring: int) -> tuple[np.ndarray, np.ndarray]:
        """Squared distance and index of the nearest point within ``ring`` buckets of each query's
        bucket (inf and N where there is none)."""
        best = np.full(len(q), np.inf)
        index = np.full(len(q), len(self), dtype=np.intp)
        for first, count, pos in self._candidates(q, ring, math.inf):
            some = np.flatnonzero(count)
            if not len(some):
                continue
            d2 = self._distances(q[first : first + len(count)], count, pos)
            seg = (np.cumsum(count) - count)[some]
            low = np.minimum.reduceat(d2, seg)
            hit = np.flatnonzero(d2 == np.repeat(low, count[some]))
            best[first + some] = low
            index[first + some] = self.order[pos[hit[np.searchsorted(hit, seg)]]]
        return best, index

    def _candidates(
        self, q: np.ndarray, ring: int, look: float
    ) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        """The points in the buckets within ``ring`` (Chebyshev) of each query's bucket that may lie
        within ``look`` cells of it (inf: all), in chunks of about :data:`CANDIDATES` pairs: (first
        query of the chunk, candidates of each of its queries, their sorted positions, query by
        query). A finite ``look`` trims each row of buckets to the part the disc reaches."""
        h, w = self.shape
        band = min(2 * ring + 1, h)  # rows of buckets a query looks at
        per = max(1, CANDIDATES // (4 * band))  # queries whose bucket ranges are set up at once
        for a in range(0, len(q), per):
            rel = (q[a : a + per] - self.lo) / self.cell  # the same arithmetic as _buckets
            ix, iy = self._clipped(rel)
            rows = np.maximum(iy - ring, 0)[:, None] + np.arange(band)
            live = rows <= np.minimum(iy + ring, h - 1)[:, None]
            if math.isfinite(look):
                # the disc's half width on each row of buckets, a little wide for the rounding
                ry = rel[:, 1, None]
                gap = np.maximum(np.maximum(rows - ry, ry - (rows + 1)) - _MARGIN, 0.0)
                half = look * look - gap * gap
                live &= half >= 0
                half = np.sqrt(np.maximum(half, 0.0)) + _MARGIN
                c0 = np.floor(rel[:, 0, None] - half)
                c1 = np.floor(rel[:, 0, None] + half)
            else:
                c0 = (ix - ring)[:, None].astype(float)
                c1 = (ix + ring)[:, None].astype(float)
            live &= (c1 >= 0) & (c0 < w)  # the row reaches the grid's columns
            c0 = np.minimum(np.maximum(c0, 0), w - 1).astype(np.intp)
            c1 = np.minimum(np.maximum(c1, 0), w - 1).astype(np.intp)
            key = np.minimum(rows, h - 1) * w
            begin = self.starts[key + c0]
            length = np.where(live, self.starts[key + c1 + 1] - begin, 0)
            count = length.sum(axis=1)
            cuts = [0, len(count)]
            if len(count) and int(count.sum()) > CANDIDATES:  # pieces of whole queries
                total = np.cumsum(count)
                at = np.searchsorted(total, np.arange(CANDIDATES, int(total[-1]), CANDIDATES), side="right")
                cuts = np.unique(np.concatenate([cuts, at])).tolist()
            for s, e in zip(cuts[:-1], cuts[1:], strict=True):
                lengths = length[s:e].ravel()
                pos = np.repeat(begin[s:e].ravel() - (np.cumsum(lengths) - lengths), lengths)
                pos += np.arange(len(pos))
                yield a + s, count[s:e], pos


def _cell_size(span: np.ndarray, n: int, cell: float | None) -> float:
    """The bucket side: ``cell``, or about two points per bucket; raised to keep the bucket count
    within bounds."""
    if cell is None or not cell > 0 or not math.isfinite(cell):
        area = float(span[0] * span[1])
        cell = math.sqrt(2.0 * area / n) if area > 0 else 2.0 * float(span.max()) / max(n, 1)
        if not cell > 0:
            cell = 1.0
    most = min(MAX_BUCKETS, max(PER_POINT * n, 4096))
    while (math.floor(span[0] / cell) + 1) * (math.floor(span[1] / cell) + 1) > most:
        cell *= 1.5
    return float(cell)


def _queries(points: np.ndarray) -> np.ndarray:
    q = np.asarray(points, dtype=float).reshape(-1, 2)
    if not np.isfinite(q).all():
        raise ValueError("query points must be finite")
    return q


def _d2(a: np.ndarray, b: np.ndarray | float) -> np.ndarray:
    d = a - b
    return np.asarray(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1])
