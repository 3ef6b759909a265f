"""Rays against line segments: the one ray/segment intersection routine of the simulated lidar, the
renderer and the simulated cameras, the lidar's fast cast built on it, a line-of-sight test, and
the distance from a point to the nearest segment (the simulated robot's collision check).

The maths. A ray ``p + t d`` (``t >= 0``) and a segment ``a + u e`` (``0 <= u <= 1``, ``e = b - a``)
meet where ``p + t d = a + u e``. With the 2-D cross product ``x × y = x_x y_y - x_y y_x`` and
``w = a - p``, crossing that equation with ``e`` and with ``d`` gives::

    t = (w × e) / (d × e),    u = (w × d) / (d × e),

defined when ``d × e != 0`` (ray and segment not parallel). ``t`` is in units of ``|d|``: metres
for a unit ``d``, the fraction of the way to a target for ``d = target - p``. Every caller computes
``t`` and ``u`` with :func:`ray_segment_params` (the same float64 expressions, so the same answers
bit for bit) and applies its own acceptance test (how close to parallel, how near the ends).
"""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.jit import compiled

__all__ = [
    "ANGLE_MARGIN",
    "EPS",
    "EVEN_TOLERANCE",
    "NEAR_SEGMENT",
    "RANGE_MARGIN",
    "SHORTEST_SEGMENT2",
    "SIGHT_END",
    "SIGHT_PARALLEL",
    "TWO_PI",
    "cast_rays",
    "nearest_segment_distance",
    "ray_segment_distances",
    "ray_segment_params",
    "segment_directions",
    "sight_blocked",
]

EPS = 1e-9  # |d × e| below this: parallel, no hit (the lidar's rule)
TWO_PI = 2.0 * math.pi

# Line of sight (:func:`sight_blocked`): the parametric tolerances at both ends of the sight line.
SIGHT_PARALLEL = 1e-12  # |d × e| below this: parallel, does not block
SIGHT_END = 1e-6  # crossings this close (as a fraction of the way) to the eye or the target do not block

# Candidate selection for :func:`cast_rays`. The final hit test and distance are computed by the same
# float64 expressions as :func:`ray_segment_distances`, so these tolerances only need to make the
# candidate ray/segment pairs a superset of the pairs that can hit; they are generous on purpose.
ANGLE_MARGIN = 1e-7  # rad added on both sides of a segment's angular interval
NEAR_SEGMENT = 1e-3  # m: segments closer than this to the origin are tested against every ray
RANGE_MARGIN = 1e-3  # m: segments farther than max_range + this cannot shorten a ray
EVEN_TOLERANCE = 1e-9  # rad: how far angles may stray from a0 + k * inc for the index arithmetic


def ray_segment_params(
    wx: np.ndarray,
    wy: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    ex: np.ndarray,
    ey: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(d × e, t, u)`` of rays ``d`` from ``p`` against segments ``a + u e`` with ``w = a - p``.

    The arguments are the components of ``w``, ``d`` and ``e`` and broadcast together: ``(R, 1)``
    rays against ``(1, S)`` segments give ``(R, S)`` answers, equal-length 1-D arrays give one
    answer per ray/segment pair. ``t`` and ``u`` are ``inf`` or ``nan`` where ``d × e == 0``.
    """
    denom = dx * ey - dy * ex
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (wx * ey - wy * ex) / denom
        u = (wx * dy - wy * dx) / denom
    return denom, t, u


def segment_directions(segments: np.ndarray) -> np.ndarray:
    """(S, 4) segments -> (S, 2) direction vectors ``e = b - a`` (what the ray tests use)."""
    directions: np.ndarray = segments[:, 2:4] - segments[:, 0:2]
    return directions


def ray_segment_distances(
    origin: np.ndarray, angles: np.ndarray, segments: np.ndarray, max_range: float
) -> np.ndarray:
    """Distance along each ray from ``origin`` at ``angles`` to the first segment hit (``max_range``
    if none): every ray against every segment, a hit being ``|d × e| > EPS``, ``t > 0`` and
    ``0 <= u <= 1`` for the unit ``d = (cos, sin)`` of the ray."""
    ranges = np.full(len(angles), max_range, dtype=float)
    if len(segments) == 0:
        return ranges
    dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]  # (R, 1)
    e = segment_directions(segments)[None, :, :]  # (1, S, 2)
    w = segments[None, :, 0:2] - origin[None, None, :]
    denom, t, u = ray_segment_params(w[..., 0], w[..., 1], dx, dy, e[..., 0], e[..., 1])
    hit = (np.abs(denom) > EPS) & (t > 0) & (u >= 0) & (u <= 1)
    t = np.where(hit, t, np.inf)
    nearest: np.ndarray = np.minimum(ranges, t.min(axis=1))
    return nearest


def sight_blocked(eye: np.ndarray, targets: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """For each of the (n, 2) ``targets``: does a segment (x1, y1, x2, y2) cross the sight line
    ``eye -> target``? ``eye`` is one point (2,) or one per target (n, 2). Here ``d = target - eye``,
    so a crossing is ``SIGHT_END < t < 1 - SIGHT_END`` with ``0 <= u <= 1`` (a segment touching the
    eye or the target itself does not block)."""
    targets = np.asarray(targets, dtype=float).reshape(-1, 2)
    segments = np.asarray(segments, dtype=float).reshape(-1, 4)
    if len(segments) == 0 or len(targets) == 0:
        return np.zeros(len(targets), dtype=bool)
    eyes = np.broadcast_to(np.asarray(eye, dtype=float).reshape(-1, 2), targets.shape)
    d = (targets - eyes)[:, None, :]  # (n, 1, 2)
    e = segment_directions(segments)[None, :, :]  # (1, S, 2)
    w = segments[None, :, 0:2] - eyes[:, None, :]
    denom, t, u = ray_segment_params(w[..., 0], w[..., 1], d[..., 0], d[..., 1], e[..., 0], e[..., 1])
    hit = (np.abs(denom) > SIGHT_PARALLEL) & (t > SIGHT_END) & (t < 1.0 - SIGHT_END) & (u >= 0.0) & (u <= 1.0)
    blocked: np.ndarray = hit.any(axis=1)
    return blocked


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


def cast_rays(
    origin: np.ndarray,
    angles: np.ndarray,
    segments: np.ndarray,
    max_range: float,
    directions: np.ndarray | None = None,
    even: tuple[float, float] | None = None,
) -> np.ndarray:
    """The result of :func:`ray_segment_distances`, without testing every ray against every segment.

    Segments that cannot come nearer than ``max_range`` are dropped; each remaining segment is
    tested only against the rays inside the angular interval it subtends from ``origin`` (found by
    index arithmetic for a full turn of evenly spaced rays, the lidar case, else by binary search
    in the sorted ray angles). The tests themselves are :func:`ray_segment_params`' expressions on
    the brute force's operands, pair by pair, so the ranges are identical to
    :func:`ray_segment_distances`'s. ``directions`` may pass precomputed :func:`segment_directions`
    of ``segments``; ``even`` the (first angle, increment) of rays the caller knows cover one turn
    evenly (a lidar), which spares checking it.
    """
    origin = np.asarray(origin, dtype=float)
    angles = np.asarray(angles, dtype=float)
    n_rays = len(angles)
    ranges = np.full(n_rays, max_range, dtype=float)
    if len(segments) == 0 or n_rays == 0:
        return ranges
    e = segment_directions(segments) if directions is None else directions
    even = even if even is not None else _full_turn(angles)
    if even is not None:
        cos, sin = np.cos(angles), np.sin(angles)
        _cast_turn(ranges, cos, sin, origin, segments, e, even[0], even[1], float(max_range))
        return ranges
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
    rays, first, last = _sorted_ray_runs(angles, start, stop)
    # A segment passing (almost) through the origin subtends about half a turn either way it is
    # computed: test it against every ray, once each.
    near = dist2 < NEAR_SEGMENT * NEAR_SEGMENT
    if near.any():
        first[near], last[near] = n_rays, 2 * n_rays
    _nearest_hits(ranges, rays, first, last, np.cos(angles), np.sin(angles), aox, aoy, ex, ey)
    return ranges


@compiled
def _cast_turn(
    ranges: np.ndarray,
    cos: np.ndarray,
    sin: np.ndarray,
    origin: np.ndarray,
    segments: np.ndarray,
    e: np.ndarray,
    a0: float,
    inc: float,
    max_range: float,
) -> None:
    """:func:`cast_rays` for rays at ``a0 + k * inc`` covering one turn, one segment at a time:
    the segment's nearest point (out of range: skipped), the rays of its angular interval by index
    arithmetic, then the brute force's test on each of them (:func:`_shorten`)."""
    n = len(ranges)
    reach2 = (max_range + RANGE_MARGIN) ** 2
    ox, oy = origin[0], origin[1]
    for i in range(len(segments)):
        sx, sy = e[i, 0], e[i, 1]
        ee = sx * sx + sy * sy
        if not ee > 0:
            continue  # zero length: never hit
        wx, wy = segments[i, 0] - ox, segments[i, 1] - oy  # exactly the brute force's ``a - origin``
        s = min(max(-(wx * sx + wy * sy) / ee, 0.0), 1.0)
        dist2 = (wx + s * sx) ** 2 + (wy + s * sy) ** 2
        if not dist2 <= reach2:
            continue
        if dist2 < NEAR_SEGMENT * NEAR_SEGMENT:
            first, last = 0, n  # through the origin: every ray, once
        else:
            bx, by = wx + sx, wy + sy
            sweep = math.atan2(wx * by - wy * bx, wx * bx + wy * by)
            start = math.atan2(wy, wx) + min(sweep, 0.0) - ANGLE_MARGIN
            stop = start + (abs(sweep) + 2.0 * ANGLE_MARGIN)
            first = int(math.ceil(((start - a0) % TWO_PI) / inc))
            last = min(first + int(math.floor((stop - start) / inc)) + 2, first + n)
        for k in range(first, last):
            _shorten(ranges, k % n, cos, sin, wx, wy, sx, sy)


def _sorted_ray_runs(
    angles: np.ndarray, start: np.ndarray, stop: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays whose angle lies in ``[start, stop]`` (mod 2 pi; each interval shorter than a turn),
    for any angles: sorted in [0, 2 pi) and written out one turn below, at and above, so that
    every interval (start in [-margin, 2 pi]) is one contiguous run.

    Returns ``(rays, first, last)``: the rays of interval ``i`` are ``rays[first[i]:last[i]]``, and
    ``rays[len(angles):2 * len(angles)]`` is every ray once.
    """
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


@compiled
def _nearest_hits(
    ranges: np.ndarray,
    rays: np.ndarray,
    first: np.ndarray,
    last: np.ndarray,
    cos: np.ndarray,
    sin: np.ndarray,
    wx: np.ndarray,
    wy: np.ndarray,
    ex: np.ndarray,
    ey: np.ndarray,
) -> None:
    """``ranges[r] = min(ranges[r], t)`` over the hits of segment ``i`` with the rays
    ``rays[first[i]:last[i]]`` (:func:`_shorten` for each pair)."""
    for i in range(len(first)):
        for k in range(first[i], last[i]):
            _shorten(ranges, rays[k], cos, sin, wx[i], wy[i], ex[i], ey[i])


@compiled
def _shorten(
    ranges: np.ndarray, r: int, cos: np.ndarray, sin: np.ndarray, wx: float, wy: float, ex: float, ey: float
) -> None:
    """``ranges[r] = min(ranges[r], t)`` when ray ``r`` hits the segment ``a + u e`` (``w = a - p``):
    :func:`ray_segment_params` and :func:`ray_segment_distances`' hit test, the same float64
    expressions in the same order, for one pair."""
    dx, dy = cos[r], sin[r]
    denom = dx * ey - dy * ex
    if abs(denom) > EPS:
        t = (wx * ey - wy * ex) / denom
        u = (wx * dy - wy * dx) / denom
        if t > 0 and u >= 0 and u <= 1 and t < ranges[r]:
            ranges[r] = t


SHORTEST_SEGMENT2 = 1e-9  # m^2: squared lengths below this count as this in nearest_segment_distance


@compiled
def nearest_segment_distance(x: float, y: float, segments: np.ndarray, cap: float) -> float:
    """Distance from ``(x, y)`` to the nearest of the (S, 4) segments, ``cap`` if none is nearer:
    the point's projection ``s = (p - a) . e / |e|^2`` clipped to [0, 1], then ``|a + s e - p|``."""
    best = cap
    for i in range(len(segments)):
        ax, ay = segments[i, 0], segments[i, 1]
        ex, ey = segments[i, 2] - ax, segments[i, 3] - ay
        s = ((x - ax) * ex + (y - ay) * ey) / max(ex * ex + ey * ey, SHORTEST_SEGMENT2)
        s = min(max(s, 0.0), 1.0)
        d = math.hypot(ax + ex * s - x, ay + ey * s - y)
        if d < best:
            best = d
    return best
