"""Straight lines in one planar laser scan: split-and-merge with least-squares refits.

Steps, in the sensor frame (x forward, y left; beam i at ``angle_min + i * angle_increment``):

1. *Points*: returns with ``RANGE_MIN < r < range_max`` (anything else is no return).
2. *Clusters* (adaptive breakpoint detector, Borges & Aldon 2004): consecutive points p_{n-1}, p_n
   belong to one surface while ``|p_n - p_{n-1}| <= r_{n-1} sin(k dphi) / sin(lambda - k dphi) + 3 sigma_r``,
   k the beams between them (up to ``max_missing + 1``: a dropout does not cut a wall), lambda the
   shallowest incidence a surface is followed at. A full turn is cut where it breaks anyway.
3. *Split* (iterative end-point fit): a cluster whose least-squares line leaves a point farther
   than ``split_distance`` is split at the point farthest from the chord of its ends.
4. *Merge*: neighbouring pieces of a cluster whose joint line fits all their points within
   ``split_distance`` are one.
5. *Refit*: total least squares (the line through the centroid c along the principal axis t,
   normal n). With N points of range noise sigma and S_tt = sum (t.(p_i - c))^2 the line's offset
   at c has variance sigma^2 / N and its angle sigma^2 / S_tt; sigma is the fit's residual
   RMS (at least ``sigma_floor``). The ends are the first and last points projected on the line.

Each segment also says what lies beyond each of its ends: the surface goes on (another piece of
its cluster), the scan sees farther there (an occluding edge: free space behind), nearer (it is
occluded), or nothing (no return). Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

RANGE_MIN = 0.05  # m: returns nearer than this are the robot itself
CONTINUES, FARTHER, NEARER, NOTHING = "continues", "farther", "nearer", "nothing"


@dataclass(frozen=True)
class LineParams:
    """Settings of the line extraction (scan_landmarks passes its own; these are the defaults)."""

    split_distance: float = 0.05  # m: a point this far off the line splits it (2.5 sigma at 2 cm)
    merge_rms: float = 0.03  # m: neighbours whose joint line fits this well (RMS, 1.5 sigma) are one
    min_points: int = 5  # points a segment needs
    max_missing: int = 2  # dropped beams a surface may have in a row without a break
    incidence: float = math.radians(10.0)  # lambda: the shallowest incidence a surface is followed at
    range_sigma: float = 0.02  # m: the lidar's range noise, for the breakpoint test
    sigma_floor: float = 0.005  # m: the least noise a fit is credited with


@dataclass(frozen=True)
class LineSegment:
    """A fitted wall line seen in one scan (sensor frame), its ends in scan order."""

    start: np.ndarray  # (2,) the first point projected on the line
    end: np.ndarray  # (2,) the last point projected on the line
    centroid: np.ndarray  # (2,)
    direction: np.ndarray  # (2,) unit, start -> end
    normal: np.ndarray  # (2,) unit, towards the sensor (the free side)
    points: int
    sigma: float  # m: residual RMS (at least sigma_floor)
    s_tt: float  # m^2: spread of the points along the line
    first: int  # beam index of the first point
    last: int  # beam index of the last point
    cluster: int
    before: str  # what lies beyond ``start``: CONTINUES, FARTHER, NEARER or NOTHING
    after: str  # beyond ``end``

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.end - self.start)))

    @property
    def var_offset(self) -> float:
        """m^2: variance of the line's offset at its centroid (sigma^2 / N)."""
        return self.sigma**2 / self.points

    @property
    def var_angle(self) -> float:
        """rad^2: variance of the line's direction (sigma^2 / S_tt)."""
        return self.sigma**2 / max(self.s_tt, 1e-12)

    def normal_variance_at(self, point: np.ndarray) -> float:
        """m^2: variance of the line's position across itself at ``point`` (offset and turn about c)."""
        s = float(self.direction @ (np.asarray(point) - self.centroid))
        return self.var_offset + s * s * self.var_angle

    def distance(self, point: np.ndarray) -> float:
        """Signed distance of ``point`` from the line, positive on the sensor's side."""
        return float(self.normal @ (np.asarray(point) - self.centroid))


def scan_points(
    ranges: np.ndarray, angle_min: float, angle_increment: float, range_max: float
) -> tuple[np.ndarray, np.ndarray]:
    """(valid mask (n,), points (n, 2)) of a scan; points of invalid beams are nan."""
    r = np.asarray(ranges, dtype=float)
    valid = np.isfinite(r) & (r > RANGE_MIN) & (r < range_max)
    angles = angle_min + angle_increment * np.arange(len(r))
    with np.errstate(invalid="ignore"):
        pts = np.column_stack([r * np.cos(angles), r * np.sin(angles)])
    pts[~valid] = np.nan
    return valid, pts


def _fit(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Total least squares: (centroid, unit direction, residuals) of (N, 2) points."""
    c = points.mean(axis=0)
    q = points - c
    cov = q.T @ q
    w, v = np.linalg.eigh(cov)
    t = v[:, 1]  # the principal axis
    n = np.array([-t[1], t[0]])
    return c, t, q @ n


def _breaks(ranges: np.ndarray, idx: np.ndarray, pts: np.ndarray, inc: float, p: LineParams) -> np.ndarray:
    """Positions j (into idx) where a new cluster starts at idx[j] (adaptive breakpoints)."""
    if len(idx) < 2:
        return np.zeros(0, dtype=int)
    k = np.diff(idx)
    dphi = np.abs(inc) * k
    step = np.hypot(*np.diff(pts, axis=0).T)
    with np.errstate(invalid="ignore", divide="ignore"):
        limit = ranges[idx[:-1]] * np.sin(dphi) / np.sin(p.incidence - dphi) + 3.0 * p.range_sigma
    broken = (k > p.max_missing + 1) | ~(dphi < p.incidence) | (step > limit)
    return np.flatnonzero(broken) + 1


def _split(points: np.ndarray, p: LineParams) -> list[tuple[int, int]]:
    """Iterative end-point fit: index ranges [i, j] (inclusive) of the pieces of one cluster."""
    out: list[tuple[int, int]] = []
    stack = [(0, len(points) - 1)]
    while stack:
        i, j = stack.pop()
        if j - i + 1 < p.min_points:
            continue
        _, _, res = _fit(points[i : j + 1])
        if np.abs(res).max() <= p.split_distance:
            out.append((i, j))
            continue
        a, b = points[i], points[j]
        chord = b - a
        length = float(np.hypot(*chord))
        run = points[i : j + 1]
        if length > 1e-9:
            off = np.abs(chord[0] * (run[:, 1] - a[1]) - chord[1] * (run[:, 0] - a[0])) / length
        else:  # a closed surface (it ends where it starts): split where it is farthest from there
            off = np.hypot(run[:, 0] - a[0], run[:, 1] - a[1])
        k = i + int(np.argmax(off[1:-1])) + 1 if j - i >= 2 else i
        if k <= i or k >= j:
            continue
        stack += [(k, j), (i, k)]  # the corner point lies on both walls
    out.sort()
    return out


def _merge(points: np.ndarray, pieces: list[tuple[int, int]], p: LineParams) -> list[tuple[int, int]]:
    merged = list(pieces)
    changed = True
    while changed and len(merged) > 1:
        changed = False
        for m in range(len(merged) - 1):
            i, j = merged[m][0], merged[m + 1][1]
            _, _, res = _fit(points[i : j + 1])
            if float(np.sqrt(np.mean(res**2))) <= p.merge_rms:
                merged[m : m + 2] = [(i, j)]
                changed = True
                break
    return merged


def _moments(points: np.ndarray) -> np.ndarray:
    """Cumulative sums (n + 1, 6) of 1, x, y, xx, xy, yy: any run's scatter in O(1)."""
    x, y = points[:, 0], points[:, 1]
    terms = np.column_stack([np.ones(len(x)), x, y, x * x, x * y, y * y])
    return np.vstack([np.zeros(6), np.cumsum(terms, axis=0)])


def _sse(cum: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Total least squares error of the runs [i, j] (inclusive): the scatter's smallest eigenvalue."""
    m = cum[j + 1] - cum[i]
    n = np.maximum(m[..., 0], 1.0)
    mx, my = m[..., 1] / n, m[..., 2] / n
    a = m[..., 3] - n * mx * mx
    b = m[..., 4] - n * mx * my
    c = m[..., 5] - n * my * my
    spread: np.ndarray = np.maximum((a + c) / 2 - np.sqrt(((a - c) / 2) ** 2 + b * b), 0.0)
    return spread


def _refine(points: np.ndarray, pieces: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Move each break between neighbouring pieces to where the two lines fit best (least total
    squared error): the end-point fit splits at the point farthest from a chord, which a stray
    point past a corner can pull a few beams off."""
    if len(pieces) < 2:
        return pieces
    cum = _moments(points)
    out = list(pieces)
    for m in range(len(out) - 1):
        i, j = out[m][0], out[m + 1][1]
        if j - i < 3:
            continue
        k = np.arange(i + 1, j - 1)  # the first piece ends at k, the second starts at k + 1
        cost = _sse(cum, np.full(len(k), i), k) + _sse(cum, k + 1, np.full(len(k), j))
        best = int(k[np.argmin(cost)])
        out[m], out[m + 1] = (i, best), (best + 1, j)
    return out


def _beyond(
    ranges: np.ndarray, valid: np.ndarray, beam: int, step: int, here: float, p: LineParams, wrap: bool
) -> str:
    """What the scan sees next to ``beam`` (one beam towards ``step``; round the turn when
    ``wrap``): farther, nearer, nothing."""
    n = len(ranges)
    for k in range(1, p.max_missing + 2):
        b = beam + step * k
        if wrap:
            b %= n
        elif not 0 <= b < n:
            return NOTHING
        if valid[b]:
            return FARTHER if ranges[b] > here + 3.0 * p.range_sigma else NEARER
    return NOTHING


def _rotation(
    valid: np.ndarray, pts: np.ndarray, ranges: np.ndarray, inc: float, p: LineParams
) -> tuple[int, bool]:
    """Where a full turn is cut, and whether it is one closed surface: after a breakpoint (the
    wrap from the last beam to the first included); a turn without one (a room seen all round)
    is cut at its farthest return, which is a corner of it (the distance from the sensor along a
    wall is largest at an end), and closed there."""
    idx = np.flatnonzero(valid)
    n = len(ranges)
    if len(idx) < 2:
        return 0, False
    circ = np.concatenate([idx, idx[:1] + n])
    cuts = _breaks(np.concatenate([ranges, ranges]), circ, pts[circ % n], inc, p)
    if len(cuts):
        return int(circ[cuts[0]] % n), False
    return int(idx[np.argmax(ranges[idx])]), True


def extract_lines(
    ranges: np.ndarray,
    angle_min: float,
    angle_increment: float,
    range_max: float,
    params: LineParams | None = None,
    full_turn: bool | None = None,
) -> list[LineSegment]:
    """The line segments of one scan, in scan order (see the module doc)."""
    p = params or LineParams()
    r = np.asarray(ranges, dtype=float)
    n = len(r)
    if full_turn is None:
        full_turn = n > 1 and abs(abs(angle_increment) * n - 2 * math.pi) < 1e-6
    valid, pts = scan_points(r, angle_min, angle_increment, range_max)
    shift, closed = _rotation(valid, pts, r, angle_increment, p) if full_turn and n else (0, False)
    order = np.roll(np.arange(n), -shift)  # beam indices in processing order
    r_o, valid_o, pts_o = r[order], valid[order], pts[order]
    idx = np.flatnonzero(valid_o)
    if len(idx) < p.min_points:
        return []
    cuts = _breaks(r_o, idx, pts_o[idx], angle_increment, p)
    bounds = np.concatenate([[0], cuts, [len(idx)]])
    segments: list[LineSegment] = []
    for c, (lo, hi) in enumerate(zip(bounds[:-1], bounds[1:], strict=True)):
        members = idx[lo:hi]
        if len(members) < p.min_points:
            continue
        if closed:  # the surface comes back to its first point: end the cluster there too
            members = np.concatenate([members, members[:1]])
        cluster_pts = pts_o[members]
        pieces = _refine(cluster_pts, _merge(cluster_pts, _split(cluster_pts, p), p))
        pieces = [(i, j) for i, j in pieces if j - i + 1 >= p.min_points]
        for m, (i, j) in enumerate(pieces):
            q = cluster_pts[i : j + 1]
            centroid, t, res = _fit(q)
            if float(t @ (q[-1] - q[0])) < 0:
                t = -t
            normal = np.array([-t[1], t[0]])
            if float(normal @ -centroid) < 0:
                normal = -normal
            along = (q - centroid) @ t
            sigma = max(float(np.sqrt(np.sum(res**2) / max(len(q) - 2, 1))), p.sigma_floor)
            first_o, last_o = int(members[i]), int(members[j])
            before = (
                CONTINUES
                if m > 0 or closed
                else _beyond(r_o, valid_o, first_o, -1, r_o[first_o], p, full_turn)
            )
            last_piece = m == len(pieces) - 1
            after = (
                CONTINUES
                if not last_piece or closed
                else _beyond(r_o, valid_o, last_o, +1, r_o[last_o], p, full_turn)
            )
            segments.append(
                LineSegment(
                    start=centroid + t * along[0],
                    end=centroid + t * along[-1],
                    centroid=centroid,
                    direction=t,
                    normal=normal,
                    points=len(q),
                    sigma=sigma,
                    s_tt=float(np.sum(along**2)),
                    first=int(order[first_o]),
                    last=int(order[last_o]),
                    cluster=c,
                    before=before,
                    after=after,
                )
            )
    return segments


__all__ = [
    "CONTINUES",
    "FARTHER",
    "NEARER",
    "NOTHING",
    "LineParams",
    "LineSegment",
    "extract_lines",
    "scan_points",
]
