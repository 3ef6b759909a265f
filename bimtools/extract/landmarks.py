"""Lidar landmarks from the BIM, no training (the paper's §5 future work): wall corners, column
corners and openings at the section height, as rows of features.csv.

Fed from the wall surfaces the extractor already computes (:mod:`bimtools.extract.floorplan`:
the boundary of the storey's solid at the cut, straight pieces with the solid on their left and
the normal into free space on their right; the rows of walls.geojson). The rules, with the
numbers of :class:`bimtools.settings.LandmarkSettings`:

- *Rings*: the pieces chain end to start into the closed outlines of the solid. Consecutive pieces
  within ``LEG_COLLINEAR`` of one direction join into a *leg* (two walls butting in one line are
  one face). Glazed pieces (windows, curtain walls) are no legs: a lidar sees through glass.
- *Corner*: where two legs meet with ``corner_angle`` between their faces (measured on the
  narrower side: 90 for a room corner and for a wall end alike) and both legs at least
  ``min_leg`` long (mouldings, frames and small jogs are not corners). Walking a ring the solid is
  on the left, so a left turn is a *convex* corner (the solid stands into free space: a wall end,
  a pillar) and a right turn a *concave* one (a room's inner corner). The normal is the bisector
  into free space, ``n = (n_a + n_b) / |n_a + n_b|`` of the two faces' normals (concave: into the
  room; convex: out of the corner). A convex corner of a free-standing outline whose minimum
  rotated rectangle is at most ``column_max_side`` each way is a *column corner*: a 2D lidar tells
  it from a wall's corner because both visible faces are that short and end in free space.
- *Opening*: two legs on one line (facing the same way, within ``LINE_TOLERANCE`` of one line),
  each at least ``min_leg`` long, with a gap of ``opening_width`` between them, and nothing nearer
  than ``min_recess`` behind the line over the middle ``OPENING_MIDDLE`` of the gap: a doorway (free
  space through the wall), or a door leaf set back in its frame (frames and architraves near the
  jambs do not count). Glass in the gap does not count either (a window is a gap to a lidar).
  Position: the gap's centre on the line; normal: the line's; Width: the gap.
- *Visible*: a point ``PROBE_DISTANCE`` along the normal must lie in a free region of at least
  ``MIN_REGION_AREA`` (not outside the building, not in a wall cavity).

IDs are ``<GlobalId>-<code><k>``: the element of the face arriving at the corner (an opening: the
face before the gap), a code per category and k counting that element's landmarks of the category
in x, y order, so features.csv stays diffable.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from bimtools.settings import LandmarkSettings
from bimtools.site.records import LANDMARK_CATEGORIES, Feature, WallSegment

LEG_COLLINEAR = math.radians(2.0)  # pieces turning less than this continue one leg
LINE_TOLERANCE = 0.03  # m: two legs this close to one line are on it (an opening's two sides)
OPENING_MIDDLE = 0.6  # the middle share of a gap that must lie min_recess behind the line
PROBE_DISTANCE = 0.3  # m along the normal: the point that must be free
MIN_REGION_AREA = 1.0  # m^2: free regions smaller than this are cavities, not places a robot sees from
ID_CODES = {"ConcaveCorner": "CC", "ConvexCorner": "CX", "ColumnCorner": "CO", "Opening": "OP"}

FreeProbe = Callable[[float, float], bool]


@dataclass
class Leg:
    """A straight run of wall surface pieces along one ring (solid on the left)."""

    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray  # unit, into free space (right of travel)
    first: WallSegment  # the piece leaving ``start``
    last: WallSegment  # the piece arriving at ``end``
    glass: bool

    @property
    def length(self) -> float:
        return float(np.hypot(*(self.end - self.start)))

    @property
    def direction(self) -> np.ndarray:
        d = self.end - self.start
        return d / max(float(np.hypot(*d)), 1e-12)


def _key(x: float, y: float) -> tuple[float, float]:
    return (round(x, 6), round(y, 6))


def chain_rings(walls: Sequence[WallSegment]) -> list[tuple[list[WallSegment], bool]]:
    """The wall pieces chained end to start: (pieces in order, closed). A piece whose end starts
    no piece or several (two outlines touching at a point) ends an open chain."""
    starts: dict[tuple[float, float], list[int]] = {}
    for i, w in enumerate(walls):
        starts.setdefault(_key(w.x1, w.y1), []).append(i)
    nxt: dict[int, int] = {}
    has_prev: set[int] = set()
    for i, w in enumerate(walls):
        after = starts.get(_key(w.x2, w.y2), [])
        if len(after) == 1 and after[0] != i:
            nxt[i] = after[0]
            has_prev.add(after[0])
    seen: set[int] = set()
    rings: list[tuple[list[WallSegment], bool]] = []
    # open chains first (from a piece nothing leads into), then the closed rings left over
    for i in [j for j in range(len(walls)) if j not in has_prev] + list(range(len(walls))):
        if i in seen:
            continue
        chain = [i]
        seen.add(i)
        closed = False
        while chain[-1] in nxt:
            j = nxt[chain[-1]]
            if j == chain[0]:
                closed = True
                break
            if j in seen:
                break
            chain.append(j)
            seen.add(j)
        rings.append(([walls[j] for j in chain], closed))
    return rings


def _piece_direction(w: WallSegment) -> np.ndarray:
    d = np.array([w.x2 - w.x1, w.y2 - w.y1])
    return d / max(float(np.hypot(*d)), 1e-12)


def _turn(a: np.ndarray, b: np.ndarray) -> float:
    """Signed angle from direction a to direction b (radians, left positive)."""
    return math.atan2(a[0] * b[1] - a[1] * b[0], float(a @ b))


def ring_legs(pieces: list[WallSegment], closed: bool) -> list[Leg]:
    """Join consecutive collinear pieces into legs; a closed ring starts at a real bend."""
    n = len(pieces)
    if n == 0:
        return []
    begin = 0
    if closed:
        for i in range(n):
            prev, here = pieces[i - 1], pieces[i]
            bend = abs(_turn(_piece_direction(prev), _piece_direction(here))) >= LEG_COLLINEAR
            if bend or prev.glass != here.glass:
                begin = i
                break
        else:
            begin = 0  # a ring without a bend (a circle finely cut): no corners
    order = [pieces[(begin + k) % n] for k in range(n)]
    legs: list[Leg] = []
    for w in order:
        start, end = np.array([w.x1, w.y1]), np.array([w.x2, w.y2])
        if legs and legs[-1].glass == w.glass:
            leg = legs[-1]
            if abs(_turn(leg.direction, _piece_direction(w))) < LEG_COLLINEAR:
                leg.end, leg.last = end, w
                d = leg.direction
                leg.normal = np.array([d[1], -d[0]])
                continue
        legs.append(Leg(start, end, np.array(w.normal, dtype=float), w, w, w.glass))
    return legs


@dataclass(frozen=True)
class _Landmark:
    category: str
    x: float
    y: float
    normal: tuple[float, float]
    width: float
    element: str
    ifc_class: str
    name: str


def _is_column(pieces: list[WallSegment], max_side: float) -> bool:
    """A closed outline of solid (walked anticlockwise: an exterior) at most max_side each way."""
    ring = np.array([[w.x1, w.y1] for w in pieces])
    if len(ring) < 3:
        return False
    x, y = ring[:, 0], ring[:, 1]
    signed = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    if signed <= 0:
        return False  # a hole of the solid: the outline of a room, not of a column
    rect = shapely.minimum_rotated_rectangle(shapely.multipoints(ring))
    coords = np.asarray(rect.exterior.coords)[:, :2] if rect.geom_type == "Polygon" else ring
    sides = np.hypot(*np.diff(coords, axis=0).T)
    return bool(len(sides) and float(sides.max()) <= max_side)


def _corners(legs: list[Leg], closed: bool, column: bool, s: LandmarkSettings) -> list[_Landmark]:
    lo, hi = s.corner_angle
    out: list[_Landmark] = []
    pairs = zip(legs, legs[1:] + legs[:1], strict=True) if closed else zip(legs, legs[1:], strict=False)
    for a, b in pairs:
        if a.glass or b.glass or a.length < s.min_leg or b.length < s.min_leg:
            continue
        turn = _turn(a.direction, b.direction)
        between = 180.0 - math.degrees(abs(turn))
        if not lo <= between <= hi:
            continue
        bisector = a.normal + b.normal
        bisector = bisector / max(float(np.hypot(*bisector)), 1e-12)
        convex = turn > 0
        category = ("ColumnCorner" if column else "ConvexCorner") if convex else "ConcaveCorner"
        kind = "column corner" if column and convex else ("convex corner" if convex else "concave corner")
        out.append(
            _Landmark(
                category,
                float(b.start[0]),
                float(b.start[1]),
                (float(bisector[0]), float(bisector[1])),
                min(a.length, b.length),
                a.last.element,
                a.last.ifc_class,
                f"{kind} {between:.0f} deg",
            )
        )
    return out


def _openings(legs: list[Leg], walls: Sequence[WallSegment], s: LandmarkSettings) -> list[_Landmark]:
    lo, hi = s.opening_width
    faces = [leg for leg in legs if not leg.glass and leg.length >= s.min_leg]
    if not faces:
        return []
    solid = [w for w in walls if not w.glass]
    lines = shapely.linestrings([[[w.x1, w.y1], [w.x2, w.y2]] for w in solid]) if solid else None
    tree = shapely.STRtree(lines) if lines is not None else None
    starts = np.array([f.start for f in faces])
    out: list[_Landmark] = []
    for a in faces:
        d, n = a.direction, a.normal
        nearest: tuple[float, Leg] | None = None  # the next face along the line
        for j in np.flatnonzero(np.hypot(*(starts - a.end).T) <= hi + LINE_TOLERANCE):
            b = faces[j]
            if b is a or abs(_turn(d, b.direction)) >= LEG_COLLINEAR:
                continue
            offset = b.start - a.end
            along = float(offset @ d)
            if (
                along > 0
                and abs(float(offset @ n)) <= LINE_TOLERANCE
                and (nearest is None or along < nearest[0])
            ):
                nearest = (along, b)
        if nearest is None or not lo <= nearest[0] <= hi:
            continue
        gap, b = nearest
        gap_vec = b.start - a.end
        # the middle of the gap: nothing from just in front of the line to min_recess behind it
        u0, u1 = 0.5 * (1 - OPENING_MIDDLE) * gap, 0.5 * (1 + OPENING_MIDDLE) * gap
        corners = [a.end + d * u + n * v for u, v in ((u0, LINE_TOLERANCE), (u1, LINE_TOLERANCE))] + [
            a.end + d * u - n * s.min_recess for u in (u1, u0)
        ]
        strip = shapely.Polygon(corners)
        if tree is not None and len(tree.query(strip, predicate="intersects")):
            continue
        depth = _depth_behind(a.end + d * (gap / 2), -n, tree, lines)
        centre = a.end + d * (gap / 2) + n * float(gap_vec @ n) / 2
        what = "through" if depth is None else f"recess {depth:.2f} m"
        out.append(
            _Landmark(
                "Opening",
                float(centre[0]),
                float(centre[1]),
                (float(n[0]), float(n[1])),
                gap,
                a.last.element,
                a.last.ifc_class,
                f"opening {gap:.2f} m ({what})",
            )
        )
    return out


RECESS_PROBE = 1.0  # m behind the line: a gap with no surface this near is a through opening


def _depth_behind(
    point: np.ndarray, back: np.ndarray, tree: shapely.STRtree | None, lines: np.ndarray | None
) -> float | None:
    """Distance from ``point`` along ``back`` to the first non-glass surface (None: none within
    RECESS_PROBE)."""
    if tree is None or lines is None:
        return None
    ray = shapely.LineString([point, point + back * RECESS_PROBE])
    hits = tree.query(ray, predicate="intersects")
    if len(hits) == 0:
        return None
    p = shapely.Point(point)
    return float(min(p.distance(ray.intersection(lines[i])) for i in hits))


def wall_landmarks(
    walls: Sequence[WallSegment], settings: LandmarkSettings, free: FreeProbe | None = None
) -> list[_Landmark]:
    """Corners and openings of one storey's wall surfaces that a lidar sees (see the module doc);
    ``free(x, y)`` says whether a point is a free place a robot could see from (None: all are)."""
    found: list[_Landmark] = []
    all_legs: list[Leg] = []
    for pieces, closed in chain_rings(walls):
        legs = ring_legs(pieces, closed)
        all_legs += legs
        column = closed and _is_column(pieces, settings.column_max_side)
        found += _corners(legs, closed, column, settings)
    found += _openings(all_legs, walls, settings)
    if free is not None:
        found = [
            m for m in found if free(m.x + PROBE_DISTANCE * m.normal[0], m.y + PROBE_DISTANCE * m.normal[1])
        ]
    return found


def storey_landmarks(
    walls: Sequence[WallSegment],
    settings: LandmarkSettings,
    storey: str,
    elevation: float,
    free: FreeProbe | None = None,
) -> list[Feature]:
    """The landmark rows of one storey, in category then x, y order, with stable IDs."""
    found = wall_landmarks(walls, settings, free)
    order = {c: i for i, c in enumerate(LANDMARK_CATEGORIES)}
    found.sort(key=lambda m: (order[m.category], round(m.x, 3), round(m.y, 3), m.element))
    counter: dict[tuple[str, str], int] = {}
    rows: list[Feature] = []
    for m in found:
        key = (m.element, m.category)
        counter[key] = counter.get(key, 0) + 1
        rows.append(
            Feature(
                id=f"{m.element}-{ID_CODES[m.category]}{counter[key]}",
                category=m.category,
                x=m.x,
                y=m.y,
                norm_x=m.normal[0],
                norm_y=m.normal[1],
                width=m.width,
                height=0.0,
                storey=storey,
                elevation=elevation,
                ifc_class=m.ifc_class,
                name=m.name,
            )
        )
    return rows


def region_probe(labels_at: Callable[[float, float], int], areas: np.ndarray) -> FreeProbe:
    """A :data:`FreeProbe` from a free-region labelling: free and at least MIN_REGION_AREA."""
    return lambda x, y: bool(areas[labels_at(x, y)] >= MIN_REGION_AREA)


__all__ = [
    "ID_CODES",
    "LINE_TOLERANCE",
    "MIN_REGION_AREA",
    "PROBE_DISTANCE",
    "chain_rings",
    "region_probe",
    "ring_legs",
    "storey_landmarks",
    "wall_landmarks",
]
