"""Lidar landmarks in one planar scan: wall corners, column corners and openings, by the rules
bim-extract applies to the BIM (:mod:`bimtools.extract.landmarks`), on the lines of
:mod:`initcli.core.scan_lines`. The sensor is at the origin, so its side of every line is free space.

- *Corner*: two neighbouring lines of one surface (one cluster) meeting at P, the intersection of
  the lines ``n_a . p = n_a . c_a`` and ``n_b . p = n_b . c_b``, within ``corner_join`` of both
  lines' near ends; the angle between the faces (from P to the far ends) in ``corner_angle``; both
  faces, P to the far end, at least ``min_leg``. *Concave* when the sensor lies inside the wedge
  the faces span (``-P = alpha a + beta b`` with alpha, beta > 0: it looks into a room's corner),
  else *convex*. Normal: the bisector into free space, ``(a + b) / |a + b|`` for a concave corner,
  its opposite for a convex one. A convex corner whose two faces are the whole surface (both far
  ends are edges with free space or nothing behind) and at most ``column_max_side`` long is a
  *column corner*.
- *Opening*: a line A, then the next line B in scan order on the same line (within ``line_angle``
  and ``line_distance``), both at least ``min_leg``, with a gap of ``opening_width`` between A's
  end and B's start (each end moved half a beam spacing into the gap: the true edge lies between
  the last return and the first miss); every beam through the middle ``OPENING_MIDDLE`` of the gap
  returns at least ``min_recess`` behind the line or nothing. Position: the gap's centre; normal:
  the line's, towards the sensor.

Covariance (sensor frame). A line's position across itself at a point s metres from its centroid
has variance ``v = sigma^2 / N + s^2 sigma^2 / S_tt`` (:class:`~initcli.core.scan_lines.LineSegment`).
A corner solves ``N p = rho`` with the normals as the rows of N, so ``Cov(P) = N^-1 diag(v_a, v_b) N^-T``.
An opening's centre: along the line ``((r_a dphi)^2 + (r_b dphi)^2) / 48 + sigma^2 / 2`` (each edge
uniform over a beam spacing, halved by the mean), across it ``(v_a + v_b) / 4``. Centimetres at
a few metres. Pure numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from initcli.core.scan_lines import CONTINUES, FARTHER, NOTHING, LineParams, LineSegment, extract_lines

OPENING_MIDDLE = 0.6  # the middle share of a gap whose beams must pass behind the line (as the BIM rule)
MIN_GAP_BEAMS = 2  # beams through that middle an opening needs


class LandmarkRules(Protocol):
    """What makes a landmark, as the categories file's ``landmarks:`` block says it
    (:class:`bimtools.extract.settings.LandmarkSettings`): angles in degrees, lengths in metres."""

    corner_angle: tuple[float, float]
    min_leg: float
    column_max_side: float
    opening_width: tuple[float, float]
    min_recess: float


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


def _corner(a: LineSegment, b: LineSegment, spacing: float, p: ScanLandmarkParams) -> ScanLandmark | None:
    crossing = line_intersection(a, b)
    if crossing is None:
        return None
    at, cov = crossing
    join = max(p.corner_join, 2.0 * spacing * float(np.hypot(*at)))
    if np.hypot(*(at - a.end)) > join or np.hypot(*(at - b.start)) > join:
        return None
    leg_a, leg_b = float(np.hypot(*(a.start - at))), float(np.hypot(*(b.end - at)))
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
    # half a beam spacing into the gap at each edge (the edge lies between a return and a miss)
    end_a = a.end + d * 0.5 * spacing * float(np.hypot(*a.end))
    start_b = b.start - d * 0.5 * spacing * float(np.hypot(*b.start))
    gap = float(d @ (start_b - end_a))
    if not p.opening_width[0] <= gap <= p.opening_width[1]:
        return None
    beams = _between(a.last, b.first, len(ranges))
    u = np.column_stack([np.cos(angles[beams]), np.sin(angles[beams])])
    towards = u @ n  # < 0: the beam heads for the line
    rho = float(n @ a.centroid)  # < 0: the line lies away from the sensor along -n
    with np.errstate(divide="ignore", invalid="ignore"):
        t_line = rho / towards
    hit = t_line[:, None] * u
    s = (hit - end_a) @ d
    middle = (towards < 0) & (s >= 0.5 * (1 - OPENING_MIDDLE) * gap) & (s <= 0.5 * (1 + OPENING_MIDDLE) * gap)
    if middle.sum() < MIN_GAP_BEAMS:
        return None
    r = ranges[beams][middle]
    returned = np.isfinite(r) & (r < range_max)
    # depth behind the line of each return along its beam, as a distance from the line
    depth = (r - t_line[middle]) * -towards[middle]
    if np.any(returned & ~(depth >= p.min_recess)):
        return None
    centre = 0.5 * (end_a + start_b)
    centre = centre - n * (a.distance(centre) + b.distance(centre)) / 2  # onto the two lines' mean
    along = ((spacing * np.hypot(*end_a)) ** 2 + (spacing * np.hypot(*start_b)) ** 2) / 48.0
    along += 0.5 * (a.sigma**2 + b.sigma**2) / 2
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
    for i, a in enumerate(segments):
        for b in segments[i + 1 : i + 1 + p.look_ahead]:
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
