"""The simulated world: the storey's obstacle outlines (from the BIM) plus unmapped clutter and
moving workers, as line segments for ray casting, occlusion and collision checks."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bimtools.site.records import Obstacle

EPS = 1e-9


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


@dataclass
class Worker:
    """A person walking back and forth between two points; stops while the robot is close."""

    a: np.ndarray
    b: np.ndarray
    speed: float = 0.8
    radius: float = 0.25
    phase: float = 0.0  # metres walked along the back-and-forth loop
    yield_distance: float = 1.2  # m: closer than this to the robot the worker waits

    def position(self, t: float = 0.0) -> np.ndarray:
        length = float(np.hypot(*(self.b - self.a))) or 1.0
        s = self.phase % (2 * length)
        s = s if s <= length else 2 * length - s
        return self.a + (self.b - self.a) * (s / length)

    def advance(self, dt: float, robot_xy: np.ndarray) -> None:
        if float(np.hypot(*(self.position() - robot_xy))) > self.yield_distance:
            self.phase += self.speed * dt


@dataclass
class SimWorld:
    """Static segments (BIM obstacles + clutter) and moving workers, with a coarse grid index."""

    static: np.ndarray  # (S, 4)
    clutter: list[np.ndarray] = field(default_factory=list)  # (5, 2) closed boxes, for plots
    workers: list[Worker] = field(default_factory=list)
    cell: float = 4.0

    def __post_init__(self) -> None:
        self._index: dict[tuple[int, int], np.ndarray] = {}
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

    def segments_near(self, x: float, y: float, radius: float) -> np.ndarray:
        """Static segments within (roughly) ``radius`` of a point."""
        if not self._index:
            return self.static
        g0 = np.floor((np.array([x, y]) - radius) / self.cell).astype(int)
        g1 = np.floor((np.array([x, y]) + radius) / self.cell).astype(int)
        ids = [
            self._index[(gx, gy)]
            for gx in range(g0[0], g1[0] + 1)
            for gy in range(g0[1], g1[1] + 1)
            if (gx, gy) in self._index
        ]
        if not ids:
            return np.zeros((0, 4))
        return self.static[np.unique(np.concatenate(ids))]

    def worker_segments(self, t: float) -> np.ndarray:
        if not self.workers:
            return np.zeros((0, 4))
        return np.concatenate([box_edges(*w.position(t), w.radius, w.radius) for w in self.workers])

    def advance(self, dt: float, robot_xy: np.ndarray) -> None:
        for worker in self.workers:
            worker.advance(dt, robot_xy)

    def segments_at(self, x: float, y: float, radius: float, t: float) -> np.ndarray:
        near = self.segments_near(x, y, radius)
        moving = self.worker_segments(t)
        return np.concatenate([near, moving]) if len(moving) else near

    def raycast(self, origin: np.ndarray, angles: np.ndarray, max_range: float, t: float) -> np.ndarray:
        segments = self.segments_at(float(origin[0]), float(origin[1]), max_range, t)
        return ray_segment_distances(np.asarray(origin, dtype=float), angles, segments, max_range)

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
