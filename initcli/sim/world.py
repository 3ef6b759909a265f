"""The simulated world: the storey's obstacle outlines (from the BIM) plus unmapped clutter and
moving workers, as line segments for ray casting, occlusion and collision checks."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from bimtools.site.records import Obstacle
from initcli.core.geometry.raycast import (
    cast_rays,
    nearest_segment_distance,
    ray_segment_params,
    segment_directions,
)
from initcli.storey.outlines import closed_ring, polygon_edges

__all__ = [
    "GLASS_ECHO_DEG",
    "NEAR_CACHE_SIZE",
    "SimWorld",
    "Worker",
    "glass_echoes",
    "world_edges",
]

NEAR_CACHE_SIZE = 256  # blocks of grid cells whose segment indices SimWorld keeps


def world_edges(obstacles: list[Obstacle], boxes: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(S, 4) segments of the obstacles' outlines (exteriors, then holes) and of the closed (n, 2)
    ``boxes``, and an (S,) mask of the glazed ones."""
    parts = [polygon_edges(closed_ring(o.exterior)) for o in obstacles]
    glazed = [np.full(len(p), o.glass) for o, p in zip(obstacles, parts, strict=True)]
    holes = [(o, polygon_edges(closed_ring(h))) for o in obstacles for h in o.holes]
    parts += [p for _, p in holes]
    glazed += [np.full(len(p), o.glass) for o, p in holes]
    parts += [polygon_edges(b) for b in boxes]
    glazed += [np.zeros(len(b) - 1, dtype=bool) for b in boxes]
    static = np.concatenate(parts) if parts else np.zeros((0, 4))
    return static, (np.concatenate(glazed) if glazed else np.zeros(0, dtype=bool))


GLASS_ECHO_DEG = 10.0  # a lidar beam returns from glass only this close to the pane's normal


def glass_echoes(origin: np.ndarray, angles: np.ndarray, panes: np.ndarray, max_range: float) -> np.ndarray:
    """Range along each ray to the first glass pane that sends the beam back: glass is transparent
    to a lidar except at near-normal incidence (within ``GLASS_ECHO_DEG``), where it reflects."""
    dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]
    e = segment_directions(panes)[None, :, :]
    length = np.maximum(np.hypot(e[..., 0], e[..., 1]), 1e-12)
    w = panes[None, :, 0:2] - origin[None, None, :]
    denom, t, u = ray_segment_params(w[..., 0], w[..., 1], dx, dy, e[..., 0], e[..., 1])
    near_normal = np.abs(denom) / length >= math.cos(
        math.radians(GLASS_ECHO_DEG)
    )  # |d x e|/|e| = cos(incidence)
    hit = near_normal & (t > 0) & (u >= 0) & (u <= 1)
    t = np.where(hit, t, np.inf)
    return np.minimum(np.full(len(angles), max_range), t.min(axis=1))


@dataclass
class Worker:
    """A person walking back and forth between two points. When the robot comes close the worker
    stops; after ``patience`` seconds of standing face to face (a narrow corridor) the worker gives
    way: walks off away from the robot for ``give_way`` seconds, as people do, beyond the end of its
    line where there is room (``room_a`` before ``a``, ``room_b`` past ``b``: a person steps out of
    the narrow stretch a robot waits at), then walks back to its line."""

    a: np.ndarray
    b: np.ndarray
    speed: float = 0.8
    radius: float = 0.25
    phase: float = 0.0  # metres walked along the back-and-forth loop at the start
    yield_distance: float = 1.2  # m: closer than this to the robot the worker waits
    patience: float = 1.0  # s standing before giving way
    give_way: float = 5.0  # s walking off, whatever the robot does
    room_a: float = 0.0  # m free before ``a`` along the line (walked only when giving way)
    room_b: float = 0.0  # m free past ``b`` along the line (walked only when giving way)
    waited: float = 0.0
    giving_way: float = 0.0
    s: float = field(init=False)  # m from ``a`` along the line (negative: before ``a``)
    heading: int = field(init=False)  # +1 toward ``b``, -1 toward ``a``

    def __post_init__(self) -> None:
        length = self.length
        p = self.phase % (2 * length)
        self.s, self.heading = (p, 1) if p <= length else (2 * length - p, -1)

    @cached_property
    def length(self) -> float:
        return float(np.hypot(*(self.b - self.a))) or 1.0  # a and b never move

    @cached_property
    def _line(self) -> tuple[float, float, float, float]:
        """a and b - a as floats (a and b never move)."""
        ax, ay = float(self.a[0]), float(self.a[1])
        return ax, ay, float(self.b[0]) - ax, float(self.b[1]) - ay

    def xy(self) -> tuple[float, float]:
        """Where the worker is: ``a + (b - a) * (s / length)``, as floats."""
        ax, ay, dx, dy = self._line
        f = self.s / self.length
        return ax + dx * f, ay + dy * f

    def position(self, t: float = 0.0) -> np.ndarray:
        return np.array(self.xy())

    def advance(self, dt: float, robot_xy: np.ndarray) -> None:
        length = self.length
        if self.giving_way > 0:
            self.giving_way -= dt
            self.s = min(max(self.s + self.heading * self.speed * dt, -self.room_a), length + self.room_b)
            return
        here = self.position()
        rx, ry = float(here[0] - robot_xy[0]), float(here[1] - robot_xy[1])
        if math.hypot(rx, ry) > self.yield_distance:
            self.waited = 0.0
            if self.s <= 0.0:  # back to its line, or round at its end
                self.heading = 1
            elif self.s >= length:
                self.heading = -1
            self.s += self.heading * self.speed * dt
            return
        self.waited += dt
        if self.waited >= self.patience:
            # Walk off along the line away from the robot (the side the worker stands on).
            _, _, dx, dy = self._line
            self.heading = 1 if rx * dx + ry * dy >= 0.0 else -1
            self.waited, self.giving_way = 0.0, self.give_way


@dataclass(frozen=True)
class _Block:
    """The static segments in one block of grid cells, in the forms their users need."""

    segments: np.ndarray  # all of them
    opaque: np.ndarray  # the non-glazed ones (the lidar's obstacles) ...
    directions: np.ndarray  # ... and their direction vectors
    glazed: np.ndarray  # the glazed ones (echo only near the normal)


@dataclass
class SimWorld:
    """Static segments (BIM obstacles + clutter) and moving workers, with a coarse grid index."""

    static: np.ndarray  # (S, 4)
    clutter: list[np.ndarray] = field(default_factory=list)  # (5, 2) closed boxes, for plots
    workers: list[Worker] = field(default_factory=list)
    cell: float = 4.0
    glass: np.ndarray | None = None  # (S,) bool: glazed segments (block motion, mostly not the lidar)

    def __post_init__(self) -> None:
        self.static = np.asarray(self.static, dtype=float).reshape(-1, 4)
        self.glass = (
            np.zeros(len(self.static), dtype=bool)
            if self.glass is None
            else np.asarray(self.glass, dtype=bool).reshape(-1)
        )
        self._directions = segment_directions(self.static)
        self._index: dict[tuple[int, int], np.ndarray] = {}
        self._blocks: dict[tuple[int, int, int, int], _Block] = {}
        self._worker_cache: tuple[tuple[tuple[float, ...], ...], np.ndarray] | None = None
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
        boxes = clutter or []
        static, glass = world_edges(obstacles, boxes)
        return SimWorld(static=static, clutter=boxes, workers=workers or [], glass=glass)

    def _near(self, x: float, y: float, radius: float) -> _Block:
        """The static segments in the grid cells within ``radius`` of a point. The answer depends
        only on the block of cells covered, so it is cached per block (the robot stays in the same
        block for many scans), the oldest dropped past NEAR_CACHE_SIZE blocks."""
        g0x, g0y = math.floor((x - radius) / self.cell), math.floor((y - radius) / self.cell)
        g1x, g1y = math.floor((x + radius) / self.cell), math.floor((y + radius) / self.cell)
        key = (g0x, g0y, g1x, g1y)
        cached = self._blocks.get(key)
        if cached is not None:
            return cached
        found = [
            self._index[(gx, gy)]
            for gx in range(g0x, g1x + 1)
            for gy in range(g0y, g1y + 1)
            if (gx, gy) in self._index
        ]
        ids = np.unique(np.concatenate(found)) if found else np.zeros(0, dtype=int)
        assert self.glass is not None
        glazed, opaque = ids[self.glass[ids]], ids[~self.glass[ids]]
        block = _Block(self.static[ids], self.static[opaque], self._directions[opaque], self.static[glazed])
        if len(self._blocks) >= NEAR_CACHE_SIZE:
            self._blocks.pop(next(iter(self._blocks)))
        self._blocks[key] = block
        return block

    def segments_near(self, x: float, y: float, radius: float) -> np.ndarray:
        """Static segments within (roughly) ``radius`` of a point."""
        return self._near(x, y, radius).segments

    def worker_segments(self, t: float) -> np.ndarray:
        """The workers' outlines (4 edges each, axis-aligned squares); the last ones are reused while
        no worker moved (the lidar, the camera and the collision check ask several times per control
        period)."""
        if not self.workers:
            return np.zeros((0, 4))
        key = tuple((w.s, w.radius) for w in self.workers)  # a worker's a and b never change
        if self._worker_cache is not None and self._worker_cache[0] == key:
            return self._worker_cache[1]
        rows: list[tuple[float, float, float, float]] = []
        for w in self.workers:
            x, y = w.xy()
            r = w.radius
            x0, y0, x1, y1 = x - r, y - r, x + r, y + r
            # box_edges(x, y, r, r)'s four edges, unrotated
            rows += [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]
        edges = np.array(rows)
        self._worker_cache = (key, edges)
        return edges

    def advance(self, dt: float, robot_xy: np.ndarray) -> None:
        for worker in self.workers:
            worker.advance(dt, robot_xy)

    def segments_at(self, x: float, y: float, radius: float, t: float) -> np.ndarray:
        near = self.segments_near(x, y, radius)
        moving = self.worker_segments(t)
        return np.concatenate([near, moving]) if len(moving) else near

    def raycast(
        self,
        origin: np.ndarray,
        angles: np.ndarray,
        max_range: float,
        t: float,
        even: tuple[float, float] | None = None,
    ) -> np.ndarray:
        """Range along each ray to the nearest static segment or worker at ``t`` (see
        :func:`initcli.core.geometry.raycast.cast_rays`, also for ``even``)."""
        origin = np.asarray(origin, dtype=float)
        block = self._near(float(origin[0]), float(origin[1]), max_range)
        static, directions, glazed = block.opaque, block.directions, block.glazed
        ranges = cast_rays(origin, angles, static, max_range, directions, even)
        moving = self.worker_segments(t)
        if len(moving):  # the nearer of the walls and the workers, ray by ray
            np.minimum(ranges, cast_rays(origin, angles, moving, max_range, even=even), out=ranges)
        if len(glazed):
            ranges = np.minimum(ranges, glass_echoes(origin, angles, glazed, max_range))
        return ranges

    def clearance(self, x: float, y: float, t: float, radius: float = 1.0) -> float:
        """Distance from a point to the nearest segment or worker (capped at ``radius``)."""
        x, y, radius = float(x), float(y), float(radius)
        static = nearest_segment_distance(x, y, self.segments_near(x, y, radius), radius)
        moving = self.worker_segments(t)
        return nearest_segment_distance(x, y, moving, static) if len(moving) else static
