"""The simulated world: the storey's obstacle outlines (from the BIM) plus unmapped clutter and
moving workers, as line segments for ray casting, occlusion and collision checks."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bimtools.site.records import Obstacle

EPS = 1e-9
TWO_PI = 2.0 * math.pi

# Candidate selection for :func:`cast_rays`. The final hit test and distance are computed by the same
# float64 expressions as :func:`ray_segment_distances`, so these tolerances only need to make the
# candidate ray/segment pairs a superset of the pairs that can hit; they are generous on purpose.
ANGLE_MARGIN = 1e-7  # rad added on both sides of a segment's angular interval
NEAR_SEGMENT = 1e-3  # m: segments closer than this to the origin are tested against every ray
RANGE_MARGIN = 1e-3  # m: segments farther than max_range + this cannot shorten a ray
BRUTE_FORCE_PAIRS = 4096  # at most this many ray x segment pairs, the brute force is quicker
EVEN_TOLERANCE = 1e-9  # rad: how far angles may stray from a0 + k * inc for the index arithmetic
NEAR_CACHE_SIZE = 256  # blocks of grid cells whose segment indices SimWorld keeps


def polygon_edges(ring: np.ndarray) -> np.ndarray:
    """(n, 2) closed ring -> (n-1, 4) segments x1, y1, x2, y2."""
    ring = np.asarray(ring, dtype=float)
    return np.column_stack([ring[:-1], ring[1:]])


def box_edges(cx: float, cy: float, half_w: float, half_h: float, yaw: float = 0.0) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    corners = np.array(
        [[-half_w, -half_h], [half_w, -half_h], [half_w, half_h], [-half_w, half_h], [-half_w, -half_h]]
    )
    rot = corners @ np.array([[c, s], [-s, c]]) + [cx, cy]
    return polygon_edges(rot)


def ray_segment_distances(
    origin: np.ndarray, angles: np.ndarray, segments: np.ndarray, max_range: float
) -> np.ndarray:
    """Distance along each ray from ``origin`` to the first segment hit (``max_range`` if none)."""
    ranges = np.full(len(angles), max_range, dtype=float)
    if len(segments) == 0:
        return ranges
    d = np.column_stack([np.cos(angles), np.sin(angles)])[:, None, :]  # (R, 1, 2)
    a = segments[None, :, 0:2]
    e = (segments[:, 2:4] - segments[:, 0:2])[None, :, :]  # (1, S, 2)
    ao = a - origin[None, None, :]
    denom = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]  # (R, S)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (ao[..., 0] * e[..., 1] - ao[..., 1] * e[..., 0]) / denom
        u = (ao[..., 0] * d[..., 1] - ao[..., 1] * d[..., 0]) / denom
    hit = (np.abs(denom) > EPS) & (t > 0) & (u >= 0) & (u <= 1)
    t = np.where(hit, t, np.inf)
    return np.minimum(ranges, t.min(axis=1))


def segment_directions(segments: np.ndarray) -> np.ndarray:
    """(S, 4) segments -> (S, 2) direction vectors ``b - a`` (what the ray tests use)."""
    return segments[:, 2:4] - segments[:, 0:2]


def _full_turn(angles: np.ndarray) -> tuple[float, float] | None:
    """(first angle, increment) when ``angles`` are ``a0 + k * inc`` covering exactly one turn, else None."""
    n = len(angles)
    if n < 2:
        return None
    a0 = float(angles[0])
    inc = TWO_PI / n
    if abs(float(angles[1]) - a0 - inc) > EVEN_TOLERANCE:
        return None
    if float(np.max(np.abs(angles - (a0 + inc * np.arange(n))))) > EVEN_TOLERANCE:
        return None
    return a0, inc


def _ray_runs(
    angles: np.ndarray, start: np.ndarray, stop: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays whose angle lies in ``[start, stop]`` (mod 2 pi; each interval shorter than a turn).

    Returns ``(rays, first, last)``: the rays of interval ``i`` are ``rays[first[i]:last[i]]``, and
    ``rays[len(angles):2 * len(angles)]`` is every ray once.
    """
    n = len(angles)
    even = _full_turn(angles)
    if even is not None:
        # Rays at a0 + k * inc: index arithmetic, over the ray indices written out twice.
        a0, inc = even
        first = np.ceil(np.mod(start - a0, TWO_PI) / inc).astype(np.intp)
        last = first + (np.floor((stop - start) / inc).astype(np.intp) + 2)
        # ``last`` above may overshoot by one or two rays: harmless (pairs are tested exactly) but
        # kept below a turn so that no ray appears twice for one segment.
        np.minimum(last, first + n, out=last)
        rays = np.arange(2 * n) % n
        return rays, first, last
    # Any angles: sorted in [0, 2 pi), written out one turn below, at and above, so that every
    # interval (start in [-margin, 2 pi]) is one contiguous run.
    phi = np.mod(angles, TWO_PI)
    order = np.argsort(phi, kind="stable")
    sorted_phi = phi[order]
    ext_phi = np.concatenate([sorted_phi - TWO_PI, sorted_phi, sorted_phi + TWO_PI])
    width = stop - start
    start = np.mod(start, TWO_PI)
    stop = start + width
    first = np.searchsorted(ext_phi, start, side="left")
    last = np.searchsorted(ext_phi, stop, side="right")
    return np.concatenate([order, order, order]), first, last


def cast_rays(
    origin: np.ndarray,
    angles: np.ndarray,
    segments: np.ndarray,
    max_range: float,
    directions: np.ndarray | None = None,
) -> np.ndarray:
    """The result of :func:`ray_segment_distances`, without testing every ray against every segment.

    Segments that cannot come nearer than ``max_range`` are dropped; each remaining segment is
    tested only against the rays inside the angular interval it subtends from ``origin`` (found by
    index arithmetic for a full turn of evenly spaced rays, the lidar case, else by binary search
    in the sorted ray angles). The tests themselves are the brute force's float64 expressions on
    the same operands, so the ranges are identical to :func:`ray_segment_distances`'s.
    ``directions`` may pass precomputed :func:`segment_directions` of ``segments``.
    """
    origin = np.asarray(origin, dtype=float)
    angles = np.asarray(angles, dtype=float)
    n_rays = len(angles)
    ranges = np.full(n_rays, max_range, dtype=float)
    if len(segments) == 0 or n_rays == 0:
        return ranges
    if n_rays * len(segments) <= BRUTE_FORCE_PAIRS:
        return ray_segment_distances(origin, angles, segments, max_range)
    e = segment_directions(segments) if directions is None else directions
    ao = segments[:, 0:2] - origin  # exactly the brute force's ``a - origin``
    ex, ey = e[:, 0], e[:, 1]
    aox, aoy = ao[:, 0], ao[:, 1]
    # Distance from the origin to each segment: drop those out of range, and zero-length ones
    # (their denominator is 0: they never hit).
    ee = ex * ex + ey * ey
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.minimum(np.maximum(-(aox * ex + aoy * ey) / ee, 0.0), 1.0)
    dist2 = (aox + s * ex) ** 2 + (aoy + s * ey) ** 2
    ids = np.flatnonzero((ee > 0) & (dist2 <= (max_range + RANGE_MARGIN) ** 2))
    if len(ids) == 0:
        return ranges
    ex, ey, aox, aoy, dist2 = ex[ids], ey[ids], aox[ids], aoy[ids], dist2[ids]
    bx, by = aox + ex, aoy + ey
    # Angular interval [start, stop] of each segment seen from the origin (less than half a turn
    # wide), widened by ANGLE_MARGIN.
    sweep = np.arctan2(aox * by - aoy * bx, aox * bx + aoy * by)
    start = np.arctan2(aoy, aox) + np.minimum(sweep, 0.0) - ANGLE_MARGIN
    stop = start + (np.abs(sweep) + 2.0 * ANGLE_MARGIN)
    rays, first, last = _ray_runs(angles, start, stop)
    # A segment passing (almost) through the origin subtends about half a turn either way it is
    # computed: test it against every ray, once each.
    near = dist2 < NEAR_SEGMENT * NEAR_SEGMENT
    if near.any():
        first[near], last[near] = n_rays, 2 * n_rays
    counts = np.maximum(last - first, 0)
    ends = np.cumsum(counts)
    total = int(ends[-1])
    if total == 0:
        return ranges
    seg = np.repeat(np.arange(len(ids)), counts)
    ray = rays[np.arange(total) + (first - (ends - counts))[seg]]
    # The brute force's expressions, pair by pair.
    dx, dy = np.cos(angles)[ray], np.sin(angles)[ray]
    pex, pey, paox, paoy = ex[seg], ey[seg], aox[seg], aoy[seg]
    denom = dx * pey - dy * pex
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (paox * pey - paoy * pex) / denom
        u = (paox * dy - paoy * dx) / denom
    hit = (np.abs(denom) > EPS) & (t > 0) & (u >= 0) & (u <= 1)
    np.minimum.at(ranges, ray[hit], t[hit])
    return ranges


@dataclass
class Worker:
    """A person walking back and forth between two points. When the robot comes close the worker
    stops; after ``patience`` seconds of standing face to face (a narrow corridor) the worker gives
    way: turns round and walks off for ``give_way`` seconds, as people do."""

    a: np.ndarray
    b: np.ndarray
    speed: float = 0.8
    radius: float = 0.25
    phase: float = 0.0  # metres walked along the back-and-forth loop
    yield_distance: float = 1.2  # m: closer than this to the robot the worker waits
    patience: float = 1.0  # s standing before giving way
    give_way: float = 5.0  # s walking off, whatever the robot does
    waited: float = 0.0
    giving_way: float = 0.0

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.b - self.a))) or 1.0

    def position(self, t: float = 0.0) -> np.ndarray:
        length = self.length
        s = self.phase % (2 * length)
        s = s if s <= length else 2 * length - s
        return self.a + (self.b - self.a) * (s / length)

    def advance(self, dt: float, robot_xy: np.ndarray) -> None:
        if self.giving_way > 0:
            self.giving_way -= dt
            self.phase += self.speed * dt
            return
        if float(np.hypot(*(self.position() - robot_xy))) > self.yield_distance:
            self.waited = 0.0
            self.phase += self.speed * dt
            return
        self.waited += dt
        if self.waited >= self.patience:
            # Turn round: the mirrored phase is the same spot walked the other way.
            self.phase = (2 * self.length - self.phase) % (2 * self.length)
            self.waited, self.giving_way = 0.0, self.give_way


@dataclass
class SimWorld:
    """Static segments (BIM obstacles + clutter) and moving workers, with a coarse grid index."""

    static: np.ndarray  # (S, 4)
    clutter: list[np.ndarray] = field(default_factory=list)  # (5, 2) closed boxes, for plots
    workers: list[Worker] = field(default_factory=list)
    cell: float = 4.0

    def __post_init__(self) -> None:
        self.static = np.asarray(self.static, dtype=float).reshape(-1, 4)
        self._directions = segment_directions(self.static)
        self._index: dict[tuple[int, int], np.ndarray] = {}
        self._near_cache: dict[tuple[int, int, int, int], np.ndarray] = {}
        if len(self.static) == 0:
            return
        lo = np.floor(np.minimum(self.static[:, 0:2], self.static[:, 2:4]) / self.cell).astype(int)
        hi = np.floor(np.maximum(self.static[:, 0:2], self.static[:, 2:4]) / self.cell).astype(int)
        buckets: dict[tuple[int, int], list[int]] = {}
        for i, (low, high) in enumerate(zip(lo, hi, strict=True)):
            for gx in range(low[0], high[0] + 1):
                for gy in range(low[1], high[1] + 1):
                    buckets.setdefault((gx, gy), []).append(i)
        self._index = {k: np.array(v) for k, v in buckets.items()}

    @staticmethod
    def from_obstacles(
        obstacles: list[Obstacle],
        clutter: list[np.ndarray] | None = None,
        workers: list[Worker] | None = None,
    ) -> SimWorld:
        parts = [polygon_edges(np.asarray(o.exterior)) for o in obstacles]
        parts += [polygon_edges(np.asarray(h)) for o in obstacles for h in o.holes]
        boxes = clutter or []
        parts += [polygon_edges(b) for b in boxes]
        static = np.concatenate(parts) if parts else np.zeros((0, 4))
        return SimWorld(static=static, clutter=boxes, workers=workers or [])

    def ids_near(self, x: float, y: float, radius: float) -> np.ndarray:
        """Sorted indices into ``static`` of the segments in the grid cells within ``radius`` of a point.

        The answer depends only on the block of cells covered, so it is cached per block (the
        robot stays in the same block for many scans).
        """
        g0x, g0y = math.floor((x - radius) / self.cell), math.floor((y - radius) / self.cell)
        g1x, g1y = math.floor((x + radius) / self.cell), math.floor((y + radius) / self.cell)
        key = (g0x, g0y, g1x, g1y)
        cached = self._near_cache.get(key)
        if cached is not None:
            return cached
        ids = [
            self._index[(gx, gy)]
            for gx in range(g0x, g1x + 1)
            for gy in range(g0y, g1y + 1)
            if (gx, gy) in self._index
        ]
        found = np.unique(np.concatenate(ids)) if ids else np.zeros(0, dtype=int)
        if len(self._near_cache) >= NEAR_CACHE_SIZE:
            self._near_cache.pop(next(iter(self._near_cache)))
        self._near_cache[key] = found
        return found

    def segments_near(self, x: float, y: float, radius: float) -> np.ndarray:
        """Static segments within (roughly) ``radius`` of a point."""
        if not self._index:
            return self.static
        ids = self.ids_near(x, y, radius)
        if len(ids) == 0:
            return np.zeros((0, 4))
        return self.static[ids]

    def worker_segments(self, t: float) -> np.ndarray:
        if not self.workers:
            return np.zeros((0, 4))
        edges = []
        for w in self.workers:
            x, y = w.position(t)
            edges.append(box_edges(x, y, w.radius, w.radius))
        return np.concatenate(edges)

    def advance(self, dt: float, robot_xy: np.ndarray) -> None:
        for worker in self.workers:
            worker.advance(dt, robot_xy)

    def segments_at(self, x: float, y: float, radius: float, t: float) -> np.ndarray:
        near = self.segments_near(x, y, radius)
        moving = self.worker_segments(t)
        return np.concatenate([near, moving]) if len(moving) else near

    def raycast(self, origin: np.ndarray, angles: np.ndarray, max_range: float, t: float) -> np.ndarray:
        """Range along each ray to the nearest static segment or worker at ``t`` (see :func:`cast_rays`)."""
        origin = np.asarray(origin, dtype=float)
        if self._index:
            ids = self.ids_near(float(origin[0]), float(origin[1]), max_range)
            static, directions = self.static[ids], self._directions[ids]
        else:
            static, directions = self.static, self._directions
        moving = self.worker_segments(t)
        if len(moving):
            static = np.concatenate([static, moving])
            directions = np.concatenate([directions, segment_directions(moving)])
        return cast_rays(origin, angles, static, max_range, directions)

    def clearance(self, x: float, y: float, t: float, radius: float = 1.0) -> float:
        """Distance from a point to the nearest segment (capped at ``radius``)."""
        segments = self.segments_at(x, y, radius, t)
        if len(segments) == 0:
            return radius
        p = np.array([x, y])
        a, b = segments[:, 0:2], segments[:, 2:4]
        ab = b - a
        s = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), EPS), 0, 1)
        closest = a + ab * s[:, None]
        return float(min(radius, np.hypot(*(closest - p).T).min()))
