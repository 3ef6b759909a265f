"""The deterministic exploration path of a survey sample: look round on the spot, then follow a wall.

The session turns once on the spot and then follows the ``side`` wall at ``wall_distance``
(:func:`initcli.core.navigation.wall_following.wall_follow`). Noise-free, the path of a wall follower is the
iso-line of the circulation area's clearance at ``wall_distance``: one closed loop per boundary
(the corridor outline, islands), traversed with the wall on the followed side. A start joins the
nearest loop point on its followed side that it can see, straight; then it follows the loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from bimtools.site.records import OccupancyGrid
from initcli.core.geometry.raycast import sight_blocked

__all__ = ["ENTRY_CANDIDATES", "Entry", "Loop", "follow_loops", "join_loop", "look_round"]

ENTRY_CANDIDATES = 24  # nearest loop points tried for a line of sight when joining a loop


@dataclass(frozen=True)
class Loop:
    """A closed wall-following path sampled every ``step`` metres (the point after the last is the first)."""

    xy: np.ndarray  # (P, 2)
    yaw: np.ndarray  # (P,) direction of travel
    step: float

    def __len__(self) -> int:
        return len(self.xy)

    @property
    def poses(self) -> np.ndarray:
        return np.column_stack([self.xy, self.yaw])


def _lookup(values: np.ndarray, grid: OccupancyGrid, xy: np.ndarray) -> np.ndarray:
    rows, cols = grid.world_to_cell(xy[:, 0], xy[:, 1])
    inside = (rows >= 0) & (rows < values.shape[0]) & (cols >= 0) & (cols < values.shape[1])
    out = np.zeros(len(xy), dtype=values.dtype)
    out[inside] = values[rows[inside], cols[inside]]
    return out


def _resample_closed(pts: np.ndarray, step: float) -> np.ndarray:
    closed = np.vstack([pts, pts[:1]])
    seg = np.hypot(*np.diff(closed, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(3, int(s[-1] // step))
    at = np.arange(n) * (s[-1] / n)
    return np.column_stack([np.interp(at, s, closed[:, 0]), np.interp(at, s, closed[:, 1])])


def follow_loops(
    region: np.ndarray,
    clearance: np.ndarray,
    grid: OccupancyGrid,
    wall_distance: float,
    side: int,
    step: float,
    min_length: float = 2.0,
) -> list[Loop]:
    """The wall-following loops of ``region`` (bool mask) at ``wall_distance`` metres from its walls.

    ``clearance`` (metres to the nearest non-free cell, same shape); ``side`` +1 keeps the wall on the
    left, -1 on the right; loops shorter than ``min_length`` metres are dropped.
    """
    inside = (region & (clearance >= wall_distance)).astype(np.uint8)
    contours, _ = cv2.findContours(inside, cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    loops: list[Loop] = []
    for contour in contours:
        cells = contour[:, 0, :]
        if len(cells) < 4:
            continue
        x, y = grid.cell_centre(cells[:, 1], cells[:, 0])
        pts = np.column_stack([x, y]).astype(float)
        k = 5  # circular moving average: the cell staircase is not the path
        kernel = np.ones(k) / k
        pts = np.column_stack(
            [np.convolve(np.concatenate([p[-k:], p, p[:k]]), kernel, "same")[k:-k] for p in pts.T]
        )
        pts = _resample_closed(pts, step)
        if len(pts) * step < min_length:
            continue
        tangent = np.roll(pts, -1, axis=0) - np.roll(pts, 1, axis=0)
        tangent /= np.maximum(np.hypot(*tangent.T), 1e-12)[:, None]
        left = np.column_stack([-tangent[:, 1], tangent[:, 0]])
        probe = 0.5 * wall_distance
        toward = _lookup(clearance, grid, pts + side * probe * left)
        away = _lookup(clearance, grid, pts - side * probe * left)
        if np.count_nonzero(toward < away) < np.count_nonzero(toward > away):
            pts = pts[::-1].copy()
            tangent = -tangent[::-1]
        loops.append(Loop(pts, np.arctan2(tangent[:, 1], tangent[:, 0]), step))
    return loops


@dataclass(frozen=True)
class Entry:
    loop: int  # index into the loops
    index: int  # loop point joined
    approach: np.ndarray  # (A, 3) poses driven from the start to the loop point (the start excluded)
    length: float  # m of the approach


def join_loop(
    start: np.ndarray, loops: list[Loop], walls: np.ndarray, side: int, step: float
) -> Entry | None:
    """Where a wall follower starting at ``start`` (x, y, yaw) reaches the loops: the nearest loop point
    on its followed side with a clear line of sight (else the nearest one in view at all)."""
    if not loops:
        return None
    owner = np.concatenate([np.full(len(lp), i) for i, lp in enumerate(loops)])
    index = np.concatenate([np.arange(len(lp)) for lp in loops])
    xy = np.concatenate([lp.xy for lp in loops])
    d = xy - start[:2]
    dist = np.hypot(d[:, 0], d[:, 1])
    heading = np.array([math.cos(start[2]), math.sin(start[2])])
    cross = heading[0] * d[:, 1] - heading[1] * d[:, 0]
    on_side = side * cross >= -0.25 * dist
    choice = -1
    for mask in (on_side, np.ones(len(xy), dtype=bool)):
        idx = np.flatnonzero(mask)
        if not len(idx):
            continue
        near = idx[np.argsort(dist[idx])[:ENTRY_CANDIDATES]]
        blocked = sight_blocked(start[:2], xy[near], walls)
        clear = near[~blocked]
        if len(clear):
            choice = int(clear[0])
            break
    if choice < 0:
        return None
    length = float(dist[choice])
    n = max(1, math.ceil(length / step))
    frac = np.arange(1, n + 1)[:, None] / n
    path = start[None, :2] + frac * d[choice][None, :]
    yaw = math.atan2(d[choice][1], d[choice][0]) if length > 1e-9 else float(start[2])
    approach = np.column_stack([path, np.full(n, yaw)])
    return Entry(int(owner[choice]), int(index[choice]), approach, length)


def look_round(start: np.ndarray, step: float) -> np.ndarray:
    """(K, 3) poses of one turn on the spot (counter-clockwise, ``step`` radians per image)."""
    n = math.ceil(2 * math.pi / step)
    yaw = start[2] + np.arange(n + 1) * (2 * math.pi / n)
    return np.column_stack([np.full(n + 1, start[0]), np.full(n + 1, start[1]), yaw])
