"""Lidar landmarks in one planar scan: wall corners, column corners and openings, by the rules
bim-extract applies to the BIM (:mod:`bimtools.extract.landmarks`), on the lines of
:mod:`initcli.core.lidar.scan_lines`. The sensor is at the origin, so its side of every line is free space.

- *Corner*: two neighbouring lines a, b of one surface (one cluster) meeting at P, the
  intersection of ``n_a . p = n_a . c_a`` and ``n_b . p = n_b . c_b``, within ``corner_join`` (or
  two beam spacings) of the step from a's last return to b's first (a wall seen at grazing
  incidence starts a long step past P; across an occluding edge P lies beside the step); the
  angle between the faces (P to their far ends) in ``corner_angle``; both faces at least
  ``min_leg`` (a face ending in an edge: half a step between returns more than its last return).
  *Concave* when the sensor lies inside the wedge the faces span (``-P = alpha u_a + beta u_b``
  with alpha, beta > 0: it looks into a room's corner), else *convex*. Normal: the bisector into
  free space, ``(u_a + u_b) / |u_a + u_b|`` for a concave corner, its opposite for a convex one.
  A convex corner whose two faces are the whole surface (both far ends are edges with free space
  or nothing behind) and at most ``column_max_side`` long is a *column corner*.
- *Opening*: a line a, then the next line b in scan order on the same line (within ``line_angle``
  and ``line_distance``), both at least ``min_leg``. Each edge of the gap is carried on over the
  returns on the line next to it (too few for a line of their own), then moved half a step
  between returns into the gap (the true edge lies between the last return and the first miss;
  the step along the line is ``ds = r dphi / cos(incidence)``, and an edge with ``ds`` above
  ``max_edge_step`` is not placed). The gap must be ``opening_width``; the returns through its
  middle ``OPENING_MIDDLE`` lie (median, against range noise) at least ``min_recess`` behind the
  line or are missing, none in front of it; and no two returns in the gap (but ``corner_join`` or
  two beam spacings at the jambs, for reveals and frames) lie on the line (the wall goes on there).
  Position: the gap's centre; normal: the line's, towards the sensor.

Covariance (sensor frame). A line's position across itself at a point s metres from its centroid
has variance ``v = sigma^2 / N + s^2 sigma^2 / S_tt`` (:class:`~initcli.core.lidar.scan_lines.LineSegment`).
A corner solves ``N p = rho`` with the normals as the rows of N, so ``Cov(P) = N^-1 diag(v_a, v_b) N^-T``.
An opening's centre: along the line ``(ds_a^2 + ds_b^2) / 48 + (sigma_a^2 + sigma_b^2) / 4`` (each
edge uniform over one step, halved by the mean), across it ``(v_a + v_b) / 4``. Centimetres at a
few metres. Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from initcli.core.lidar.scan_lines import CONTINUES, FARTHER, NOTHING, LineParams, LineSegment, extract_lines

OPENING_MIDDLE = 0.6  # the middle share of a gap whose beams must pass behind the line (as the BIM rule)
MIN_GAP_BEAMS = 2  # beams through that middle an opening needs


class LandmarkRules(Protocol):
    """What makes a landmark, as the categories file's ``landmarks:`` block says it
    (:class:`bimtools.settings.LandmarkSettings`): angles in degrees, lengths in metres."""

    @property
    def corner_angle(self) -> tuple[float, float]: ...
    @property
    def min_leg(self) -> float: ...
    @property
    def column_max_side(self) -> float: ...
    @property
    def opening_width(self) -> tuple[float, float]: ...
    @property
    def min_recess(self) -> float: ...


@dataclass(frozen=True)
class ScanLandmarkParams:
    """The landmark rules (no defaults here: they are the site's, see :meth:`from_rules`) and the
    scan's own settings."""

    corner_angle: tuple[float, float]  # rad: between the two faces
    min_leg: float  # m
    column_max_side: float  # m
    opening_width: tuple[float, float]  # m
    min_recess: float  # m
    lines: LineParams = LineParams()
    corner_join: float = 0.1  # m (at least two beam spacings): how near P must be to both lines' ends
    line_angle: float = math.radians(4.0)  # an opening's two sides differ in direction at most this
    line_distance: float = 0.06  # m: ... and in offset at most this (3 sigma of 2 cm noise)
    look_ahead: int = 8  # lines after A searched for its other side (room behind a doorway between)
    max_edge_step: float = (
        0.15  # m: an opening's edge seen with returns farther apart along the line is not placed
    )

    @staticmethod
    def from_rules(rules: LandmarkRules, **scan: object) -> ScanLandmarkParams:
        """The rules of a categories file's ``landmarks:`` block, plus scan settings by keyword."""
        lo, hi = rules.corner_angle
        return ScanLandmarkParams(
            corner_angle=(math.radians(lo), math.radians(hi)),
            min_leg=rules.min_leg,
            column_max_side=rules.column_max_side,
            opening_width=tuple(rules.opening_width),  # type: ignore[arg-type]
            min_recess=rules.min_recess,
            **scan,  # type: ignore[arg-type]
        )


@dataclass(frozen=True)
class ScanLandmark:
    """A landmark seen in one scan, in the sensor frame."""

    category: str  # ConcaveCorner, ConvexCorner, ColumnCorner or Opening (bimtools.site.records)
    x: float
    y: float
    normal: tuple[float, float]  # unit, into free space
    width: float  # m: the shorter face of a corner, the gap of an opening
    cov: np.ndarray  # (2, 2) m^2

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])

    @property
    def range(self) -> float:
        return math.hypot(self.x, self.y)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / max(float(np.hypot(*v)), 1e-12)


def line_intersection(a: LineSegment, b: LineSegment) -> tuple[np.ndarray, np.ndarray] | None:
    """(P, Cov(P)) where the lines of a and b cross; None when (nearly) parallel."""
    normals = np.array([a.normal, b.normal])
    det = float(np.linalg.det(normals))
    if abs(det) < 1e-6:
        return None
    rho = np.array([a.normal @ a.centroid, b.normal @ b.centroid])
    inv = np.linalg.inv(normals)
    p = inv @ rho
    var = np.diag([a.normal_variance_at(p), b.normal_variance_at(p)])
    return p, inv @ var @ inv.T


def _to_segment(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance from ``point`` to the segment a-b."""
    e = b - a
    s = float(np.clip((point - a) @ e / max(float(e @ e), 1e-18), 0.0, 1.0))
    return float(np.hypot(*(a + s * e - point)))


def _corner(a: LineSegment, b: LineSegment, spacing: float, p: ScanLandmarkParams) -> ScanLandmark | None:
    crossing = line_intersection(a, b)
    if crossing is None:
        return None
    at, cov = crossing
    # P lies where the surface turns: within corner_join (or two beam spacings) of the step from
    # a's last return to b's first (long where a wall is seen at grazing incidence; across an
    # occluding edge P lies off it, beside the step)
    join = max(p.corner_join, 2.0 * spacing * float(np.hypot(*at)))
    if _to_segment(at, a.end, b.start) > join:
        return None
    leg_a, leg_b = float(np.hypot(*(a.start - at))), float(np.hypot(*(b.end - at)))
    # a face that ends in an edge goes on for half a step between returns past its last one
    if a.before in (FARTHER, NOTHING):
        leg_a += 0.5 * _step_along(a.start, a.normal, spacing)
    if b.after in (FARTHER, NOTHING):
        leg_b += 0.5 * _step_along(b.end, b.normal, spacing)
    if min(leg_a, leg_b) < p.min_leg:
        return None
    ua, ub = _unit(a.start - at), _unit(b.end - at)
    between = math.acos(max(-1.0, min(1.0, float(ua @ ub))))
    if not p.corner_angle[0] <= between <= p.corner_angle[1]:
        return None
    alpha, beta = np.linalg.solve(np.column_stack([ua, ub]), -at)
    concave = alpha > 0 and beta > 0
    bisector = _unit(ua + ub) * (1.0 if concave else -1.0)
    whole = a.before in (FARTHER, NOTHING) and b.after in (FARTHER, NOTHING)
    if concave:
        category = "ConcaveCorner"
    elif whole and max(leg_a, leg_b) <= p.column_max_side:
        category = "ColumnCorner"
    else:
        category = "ConvexCorner"
    return ScanLandmark(
        category, float(at[0]), float(at[1]), (float(bisector[0]), float(bisector[1])), min(leg_a, leg_b), cov
    )


def _step_along(point: np.ndarray, normal: np.ndarray, spacing: float) -> float:
    """m between neighbouring beams' returns along a line near ``point``: r dphi / cos(incidence)."""
    r = float(np.hypot(*point))
    cos = abs(float(normal @ point)) / max(r, 1e-12)
    return spacing * r / max(cos, 1e-6)


def _between(first: int, last: int, n: int) -> np.ndarray:
    """Beam indices strictly after ``first`` and before ``last`` in scan order (wrapping round)."""
    count = (last - first) % n - 1
    return (first + 1 + np.arange(max(count, 0))) % n


def _opening(
    a: LineSegment,
    b: LineSegment,
    ranges: np.ndarray,
    angles: np.ndarray,
    range_max: float,
    spacing: float,
    p: ScanLandmarkParams,
) -> ScanLandmark | None:
    d, n = a.direction, a.normal
    if min(a.length, b.length) < p.min_leg:
        return None
    beams = _between(a.last, b.first, len(ranges))
    u = np.column_stack([np.cos(angles[beams]), np.sin(angles[beams])])
    towards = u @ n  # < 0: the beam heads for the line
    rho = float(n @ a.centroid)  # < 0: the line lies away from the sensor along -n
    with np.errstate(divide="ignore", invalid="ignore"):
        t_line = rho / towards
    s = (t_line[:, None] * u - a.end) @ d  # where each beam crosses the line, from a's end
    r = ranges[beams]
    returned = np.isfinite(r) & (r < range_max)
    with np.errstate(invalid="ignore"):
        depth = (r - t_line) * -towards  # how far behind the line each return lies
    ahead = towards < 0
    # Returns on the line next to a's end or b's start (too few for a line of their own) are wall:
    # where they lie along the line (a reveal's return lies at its jamb wherever the beam crosses).
    with np.errstate(invalid="ignore"):
        along = (r[:, None] * u - a.end) @ d
    on_line = np.sort(along[ahead & returned & (np.abs(depth) <= p.line_distance)])
    step = 3.0 * spacing * float(np.hypot(*a.end))
    lo, hi = 0.0, float(d @ (b.start - a.end))
    for v in on_line:
        if lo < v <= lo + step:
            lo = float(v)
    for v in on_line[::-1]:
        if hi - step <= v < hi:
            hi = float(v)
    # Half a beam spacing along the line into the gap at each edge (the edge lies between a return
    # and a miss); the spacing along the line grows as 1 / cos(incidence): an edge seen at grazing
    # incidence is too uncertain to place (more than max_edge_step between returns).
    step_a, step_b = _step_along(a.end + d * lo, n, spacing), _step_along(a.end + d * hi, n, spacing)
    if max(step_a, step_b) > p.max_edge_step:
        return None
    end_a = a.end + d * (lo + 0.5 * step_a)
    start_b = a.end + d * (hi - 0.5 * step_b)
    gap = float(d @ (start_b - end_a))
    if not p.opening_width[0] <= gap <= p.opening_width[1]:
        return None
    s = s - float(d @ (end_a - a.end))  # from the gap's first edge
    edge = max(p.corner_join, 2.0 * spacing * float(np.hypot(*end_a)))  # the jambs' reveals, frames
    along = along - float(d @ (end_a - a.end))
    in_gap = ahead & (along >= edge) & (along <= gap - edge)
    if np.sum(in_gap & returned & (np.abs(depth) <= p.line_distance)) >= 2:
        return None  # the wall goes on into the gap: a or b was cut short
    middle = ahead & (s >= 0.5 * (1 - OPENING_MIDDLE) * gap) & (s <= 0.5 * (1 + OPENING_MIDDLE) * gap)
    if middle.sum() < MIN_GAP_BEAMS:
        return None
    behind = np.where(returned, depth, np.inf)[middle]  # no return: nothing behind (a doorway)
    if float(np.median(behind)) < p.min_recess or np.any(behind < -p.line_distance):
        return None  # the gap's floor is (half) the wall line, or something stands in front of it
    centre = 0.5 * (end_a + start_b)
    centre = centre - n * (a.distance(centre) + b.distance(centre)) / 2  # onto the two lines' mean
    along = (step_a**2 + step_b**2) / 48.0 + (a.sigma**2 + b.sigma**2) / 4.0
    across = (a.normal_variance_at(centre) + b.normal_variance_at(centre)) / 4.0
    frame = np.column_stack([d, n])
    cov = frame @ np.diag([along, across]) @ frame.T
    return ScanLandmark("Opening", float(centre[0]), float(centre[1]), (float(n[0]), float(n[1])), gap, cov)


def _collinear(a: LineSegment, b: LineSegment, p: ScanLandmarkParams) -> bool:
    if float(a.direction @ b.direction) < math.cos(p.line_angle):
        return False
    return abs(a.distance(b.start)) <= p.line_distance and abs(a.distance(b.end)) <= p.line_distance


def landmarks_from_lines(
    segments: list[LineSegment],
    ranges: np.ndarray,
    angle_min: float,
    angle_increment: float,
    range_max: float,
    p: ScanLandmarkParams,
) -> list[ScanLandmark]:
    """Corners and openings of one scan from its lines (in scan order)."""
    r = np.asarray(ranges, dtype=float)
    angles = angle_min + angle_increment * np.arange(len(r))
    spacing = abs(angle_increment)
    out: list[ScanLandmark] = []
    pairs = list(zip(segments, segments[1:], strict=False))
    if len(segments) > 2 and segments[-1].after == CONTINUES and segments[0].before == CONTINUES:
        pairs.append((segments[-1], segments[0]))  # a surface closed all round (a room seen whole)
    for a, b in pairs:
        if a.cluster == b.cluster and a.after == CONTINUES:
            corner = _corner(a, b, spacing, p)
            if corner is not None:
                out.append(corner)
    full_turn = abs(spacing * len(r) - 2 * math.pi) < 1e-6  # the lines go round: look past the last
    count = len(segments)
    for i, a in enumerate(segments):
        ahead = range(i + 1, min(i + 1 + p.look_ahead, i + count if full_turn else count))
        for b in (segments[k % count] for k in ahead):
            if _collinear(a, b, p):
                found = _opening(a, b, r, angles, range_max, spacing, p)
                if found is not None:
                    out.append(found)
                break
    return out


def scan_landmarks(
    ranges: np.ndarray, angle_min: float, angle_increment: float, range_max: float, p: ScanLandmarkParams
) -> list[ScanLandmark]:
    """Corners and openings in one scan (sensor frame): lines, then the rules above."""
    segments = extract_lines(ranges, angle_min, angle_increment, range_max, p.lines)
    return landmarks_from_lines(segments, ranges, angle_min, angle_increment, range_max, p)


__all__ = [
    "LandmarkRules",
    "ScanLandmark",
    "ScanLandmarkParams",
    "landmarks_from_lines",
    "line_intersection",
    "scan_landmarks",
]
