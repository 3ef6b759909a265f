"""Pure plan descriptions of the three sample floors (no IFC here).

A floor plan is a set of axis-aligned rectangles ("cells": corridor, lobby, room, unit, lift shaft,
stair enclosure) that do not overlap, plus doors on cell boundaries, lifts in shafts and stair
flights in enclosures. Walls are *derived* from the cell boundaries (:func:`wall_pieces`):

- a 0.2 m wall is centred on every boundary line between two cells, and on every boundary line
  with only one cell next to it (the exterior envelope);
- no wall separates two circulation cells (corridor/lobby), so corridors open into lobbies and
  into each other;
- collinear, touching boundary pieces are merged into one long straight wall.

Coordinates are metres in the storey frame (x east, y north); the storey sits at elevation 0.
The ground truth of the extractor tests is derived from the same description (:func:`truth_features`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Literal

from bimtools.site.records import Feature

__all__ = [
    "CIRCULATION_KINDS",
    "Cell",
    "CellKind",
    "DOOR_CLEARANCE",
    "DOOR_SIZES",
    "DoorRole",
    "DoorSpec",
    "FloorPlan",
    "LiftSpec",
    "ROLE_CATEGORY",
    "SIDE_NORMAL",
    "STOREY_ELEVATION",
    "STOREY_HEIGHT",
    "STOREY_NAME",
    "Side",
    "StairSpec",
    "Vec",
    "WALL_THICKNESS",
    "WallPiece",
    "check_plan",
    "free_points",
    "host_wall",
    "round_um",
    "truth_document",
    "truth_features",
    "wall_pieces",
    "wall_points",
]

WALL_THICKNESS = 0.2
STOREY_HEIGHT = 3.0
STOREY_NAME = "Level 1"
STOREY_ELEVATION = 0.0
# A door must stay this far (metres, beyond the wall faces) from any wall end or crossing wall.
DOOR_CLEARANCE = 0.2

CellKind = Literal["corridor", "lobby", "room", "unit", "lift_shaft", "stair_enclosure"]
DoorRole = Literal["room", "gate", "lift", "stair", "exit"]
Side = Literal["N", "S", "E", "W"]
Vec = tuple[float, float]

CIRCULATION_KINDS: frozenset[str] = frozenset({"corridor", "lobby"})
# The Table 1 category of a door of each role.
ROLE_CATEGORY: dict[str, str] = {
    "room": "Door",
    "gate": "Door",
    "exit": "Door",
    "lift": "Lift",
    "stair": "Stairs",
}
# Outward unit normal of each side of a rectangle.
SIDE_NORMAL: dict[str, tuple[int, int]] = {"N": (0, 1), "S": (0, -1), "E": (1, 0), "W": (-1, 0)}


def round_um(value: float) -> float:
    """Round a coordinate to the micrometre so float noise never reaches the files."""
    return round(value, 6) + 0.0


@dataclass(frozen=True)
class Cell:
    """An axis-aligned rectangle of the plan, bounded by wall centre lines."""

    name: str
    kind: CellKind
    x0: float
    y0: float
    x1: float
    y1: float
    long_name: str = ""

    @property
    def is_circulation(self) -> bool:
        return self.kind in CIRCULATION_KINDS

    @property
    def centre(self) -> Vec:
        return (round_um((self.x0 + self.x1) / 2), round_um((self.y0 + self.y1) / 2))

    @property
    def size(self) -> Vec:
        return (round_um(self.x1 - self.x0), round_um(self.y1 - self.y0))

    @property
    def long_length(self) -> float:
        """Length along the longer axis (a corridor cell's centre-line length)."""
        return max(self.size)

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        return self.x0 + margin < x < self.x1 - margin and self.y0 + margin < y < self.y1 - margin


@dataclass(frozen=True)
class DoorSpec:
    """A door centred at ``(x, y)`` on a cell boundary line.

    ``normal`` is the axis unit vector perpendicular to the wall pointing to the circulation side;
    ``leads_to`` names the cell on the other side ("" for the exterior).
    """

    name: str
    role: DoorRole
    x: float
    y: float
    normal: tuple[int, int]
    width: float
    height: float
    leads_to: str
    tag: str = ""

    @property
    def along(self) -> tuple[int, int]:
        """The door's local X axis (along the wall); (along, normal, up) is right-handed."""
        return (self.normal[1], -self.normal[0])

    @property
    def category(self) -> str:
        return ROLE_CATEGORY[self.role]

    @property
    def face_centre(self) -> Vec:
        """Centre of the door face on the circulation side (the feature's X, Y)."""
        half = WALL_THICKNESS / 2
        return (round_um(self.x + half * self.normal[0]), round_um(self.y + half * self.normal[1]))


@dataclass(frozen=True)
class LiftSpec:
    """A lift car (IfcTransportElement) standing in the shaft cell ``shaft``."""

    name: str
    shaft: str
    landing_door: str  # tag of the landing door
    car_width: float = 1.6  # along the landing-door wall
    car_depth: float = 1.4
    car_height: float = 2.4


@dataclass(frozen=True)
class StairSpec:
    """A straight flight rising from the storey floor to the storey height.

    ``start`` is the centre of the bottom step's nosing line at floor level, ``direction`` the
    axis unit vector of the climb.
    """

    name: str
    enclosure: str
    start: Vec
    direction: tuple[int, int]
    width: float
    risers: int
    going: float

    @property
    def run(self) -> float:
        return round_um(self.risers * self.going)

    @property
    def riser_height(self) -> float:
        return STOREY_HEIGHT / self.risers


@dataclass(frozen=True)
class WallPiece:
    """A straight wall on a boundary line: along x at ``y = coord`` (axis "x") or along y at ``x = coord``.

    ``lo``/``hi`` are the ends of the centre line on the boundary; the built wall is extended by
    half the thickness at both ends so corners and T-junctions close.
    """

    axis: Literal["x", "y"]
    coord: float
    lo: float
    hi: float
    external: bool

    @property
    def length(self) -> float:
        return round_um(self.hi - self.lo)

    def point(self, t: float) -> Vec:
        """The centre-line point at distance ``t`` from ``lo``."""
        s = round_um(self.lo + t)
        return (s, self.coord) if self.axis == "x" else (self.coord, s)


@dataclass(frozen=True)
class FloorPlan:
    name: str
    title: str
    building: str
    cells: tuple[Cell, ...]
    doors: tuple[DoorSpec, ...]
    lifts: tuple[LiftSpec, ...] = ()
    stairs: tuple[StairSpec, ...] = ()
    with_spaces: bool = False
    description: str = ""
    # Openings in walls that no door fills (gates standing open, a doorway without a leaf), as doors
    # are placed (``normal`` to the circulation side); never features.
    openings: tuple[DoorSpec, ...] = ()
    with_slab: bool = False  # a floor slab (IfcSlab) under every cell, its top at the storey's floor

    def cell(self, name: str) -> Cell:
        return next(c for c in self.cells if c.name == name)

    @property
    def corridor_length(self) -> float:
        """Sum of the corridor cells' lengths along their long axis (cells never overlap)."""
        return round_um(sum(c.long_length for c in self.cells if c.kind == "corridor"))

    def door(self, tag: str) -> DoorSpec:
        return next(d for d in self.doors if d.tag == tag)


# --------------------------------------------------------------------------------------------
# Walls from cell boundaries
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Edge:
    coord: float  # the boundary line
    lo: float
    hi: float
    cell: Cell
    positive: bool  # the cell lies on the + side of the line


def _edges(cells: Iterable[Cell], axis: str) -> list[_Edge]:
    """Cell sides running along ``axis`` ("x": bottom and top sides, "y": left and right sides)."""
    out: list[_Edge] = []
    for c in cells:
        if axis == "x":
            out += [_Edge(c.y0, c.x0, c.x1, c, True), _Edge(c.y1, c.x0, c.x1, c, False)]
        else:
            out += [_Edge(c.x0, c.y0, c.y1, c, True), _Edge(c.x1, c.y0, c.y1, c, False)]
    return out


def _is_wall(plus: Cell | None, minus: Cell | None) -> bool:
    if plus is None or minus is None:
        return True
    return not (plus.is_circulation and minus.is_circulation)


def _walls_on_line(axis: Literal["x", "y"], coord: float, edges: list[_Edge]) -> list[WallPiece]:
    cuts = sorted({round_um(v) for e in edges for v in (e.lo, e.hi)})
    pieces: list[WallPiece] = []
    for a, b in zip(cuts, cuts[1:], strict=False):
        mid = (a + b) / 2
        plus = next((e.cell for e in edges if e.positive and e.lo < mid < e.hi), None)
        minus = next((e.cell for e in edges if not e.positive and e.lo < mid < e.hi), None)
        if (plus is None and minus is None) or not _is_wall(plus, minus):
            continue
        external = plus is None or minus is None
        if pieces and pieces[-1].hi == a:
            last = pieces.pop()
            pieces.append(WallPiece(axis, coord, last.lo, b, last.external or external))
        else:
            pieces.append(WallPiece(axis, coord, a, b, external))
    return pieces


def wall_pieces(plan: FloorPlan) -> list[WallPiece]:
    """All straight walls of the plan, merged along their boundary lines, in a stable order."""
    pieces: list[WallPiece] = []
    axes: tuple[Literal["x", "y"], ...] = ("x", "y")
    for axis in axes:
        by_line: dict[float, list[_Edge]] = {}
        for edge in _edges(plan.cells, axis):
            by_line.setdefault(round_um(edge.coord), []).append(edge)
        for coord in sorted(by_line):
            pieces += _walls_on_line(axis, coord, by_line[coord])
    return pieces


def host_wall(plan: FloorPlan, door: DoorSpec, walls: list[WallPiece] | None = None) -> WallPiece:
    """The wall piece the door sits in."""
    axis = "x" if door.normal[0] == 0 else "y"
    coord, s = (door.y, door.x) if axis == "x" else (door.x, door.y)
    for w in walls if walls is not None else wall_pieces(plan):
        if w.axis == axis and math.isclose(w.coord, coord, abs_tol=1e-6) and w.lo < s < w.hi:
            return w
    raise ValueError(f"{plan.name}: door {door.tag} at ({door.x}, {door.y}) is on no wall")


# --------------------------------------------------------------------------------------------
# Plan checks
# --------------------------------------------------------------------------------------------


def _cell_at(plan: FloorPlan, x: float, y: float) -> Cell | None:
    return next((c for c in plan.cells if c.contains(x, y)), None)


def _overlaps(a: Cell, b: Cell) -> bool:
    eps = 1e-9
    return a.x0 < b.x1 - eps and b.x0 < a.x1 - eps and a.y0 < b.y1 - eps and b.y0 < a.y1 - eps


def check_plan(plan: FloorPlan) -> list[str]:
    """Everything wrong with a plan (empty when it is consistent)."""
    problems: list[str] = []
    for i, a in enumerate(plan.cells):
        problems += [f"cells {a.name} and {b.name} overlap" for b in plan.cells[i + 1 :] if _overlaps(a, b)]
    if len({c.name for c in plan.cells}) != len(plan.cells):
        problems.append("duplicate cell names")
    walls = wall_pieces(plan)
    for door in (*plan.doors, *plan.openings):
        problems += _door_problems(plan, door, walls)
    for lift in plan.lifts:
        if plan.cell(lift.shaft).kind != "lift_shaft":
            problems.append(f"{lift.name}: {lift.shaft} is not a lift shaft")
        if plan.door(lift.landing_door).leads_to != lift.shaft:
            problems.append(f"{lift.name}: landing door does not open into its shaft")
    for stair in plan.stairs:
        problems += _stair_problems(plan, stair)
    return problems


def _door_problems(plan: FloorPlan, door: DoorSpec, walls: list[WallPiece]) -> list[str]:
    probe = WALL_THICKNESS / 2 + 0.05
    front = _cell_at(plan, door.x + probe * door.normal[0], door.y + probe * door.normal[1])
    back = _cell_at(plan, door.x - probe * door.normal[0], door.y - probe * door.normal[1])
    problems = []
    if front is None or not front.is_circulation:
        problems.append(f"door {door.tag}: normal does not point into a corridor or lobby")
    behind = back.name if back else ""
    if behind != door.leads_to:
        problems.append(f"door {door.tag}: leads to {behind or 'outside'!r}, not {door.leads_to!r}")
    try:
        wall = host_wall(plan, door, walls)
    except ValueError as exc:
        return problems + [str(exc)]
    s = door.x if wall.axis == "x" else door.y
    lo, hi = s - door.width / 2, s + door.width / 2
    keep = WALL_THICKNESS / 2 + DOOR_CLEARANCE
    if lo - wall.lo < keep or wall.hi - hi < keep:
        problems.append(f"door {door.tag}: too close to the end of its wall")
    for other in walls:
        touches = other.axis != wall.axis and other.lo - keep <= wall.coord <= other.hi + keep
        if touches and lo - keep < other.coord < hi + keep:
            problems.append(f"door {door.tag}: too close to the crossing wall at {other.coord}")
    return problems


def _stair_problems(plan: FloorPlan, stair: StairSpec) -> list[str]:
    box = plan.cell(stair.enclosure)
    if box.kind != "stair_enclosure":
        return [f"{stair.name}: {stair.enclosure} is not a stair enclosure"]
    (sx, sy), (dx, dy), half = stair.start, stair.direction, stair.width / 2
    ex, ey = sx + dx * stair.run, sy + dy * stair.run
    corners = [(x + dy * k * half, y - dx * k * half) for x, y in ((sx, sy), (ex, ey)) for k in (-1, 1)]
    inside = all(box.contains(x, y, margin=WALL_THICKNESS / 2 - 1e-9) for x, y in corners)
    return [] if inside else [f"{stair.name}: flight leaves its enclosure"]


# --------------------------------------------------------------------------------------------
# Ground truth
# --------------------------------------------------------------------------------------------


def truth_features(plan: FloorPlan, guids: Mapping[str, str]) -> list[Feature]:
    """One feature per door (``guids``: door tag -> the IfcDoor's GlobalId)."""
    features = []
    for door in plan.doors:
        x, y = door.face_centre
        features.append(
            Feature(
                id=guids[door.tag],
                category=door.category,
                x=x,
                y=y,
                norm_x=float(door.normal[0]),
                norm_y=float(door.normal[1]),
                width=door.width,
                height=door.height,
                storey=STOREY_NAME,
                elevation=STOREY_ELEVATION,
                ifc_class="IfcDoor",
                name=door.name,
            )
        )
    return features


def _distance_to_wall(walls: Iterable[WallPiece], x: float, y: float) -> float:
    """Distance from a point to the nearest wall body (extended ends included)."""
    best = math.inf
    half = WALL_THICKNESS / 2
    for w in walls:
        s, c = (x, y) if w.axis == "x" else (y, x)
        ds = max(w.lo - half - s, 0.0, s - w.hi - half)
        dc = max(abs(c - w.coord) - half, 0.0)
        best = min(best, math.hypot(ds, dc))
    return best


def free_points(plan: FloorPlan, step: float = 5.0, clearance: float = 0.5) -> list[Vec]:
    """Points on corridor centre lines (and lobby centres), at least ``clearance`` from any wall."""
    walls = wall_pieces(plan)
    candidates: list[Vec] = []
    for cell in plan.cells:
        if cell.kind == "lobby":
            candidates.append(cell.centre)
        elif cell.kind == "corridor":
            (cx, cy), (w, h) = cell.centre, cell.size
            n = max(1, int((max(w, h) - 2.0) // step) + 1)
            span = (n - 1) * step
            for i in range(n):
                t = -span / 2 + i * step
                candidates.append((round_um(cx + t), cy) if w >= h else (cx, round_um(cy + t)))
    return [p for p in candidates if _distance_to_wall(walls, *p) >= clearance]


def wall_points(plan: FloorPlan, clearance: float = 0.6) -> list[Vec]:
    """One point per wall piece in the middle of the wall thickness, away from openings."""
    walls = wall_pieces(plan)
    spans: dict[WallPiece, list[tuple[float, float]]] = {}
    for door in (*plan.doors, *plan.openings):
        s = door.x if door.normal[0] == 0 else door.y
        spans.setdefault(host_wall(plan, door, walls), []).append((s - door.width / 2, s + door.width / 2))
    points: list[Vec] = []
    for w in walls:
        for frac in (0.5, 0.3, 0.7, 0.15, 0.85):
            s = w.lo + frac * w.length
            if all(not (a - clearance < s < b + clearance) for a, b in spans.get(w, [])):
                points.append(w.point(frac * w.length))
                break
    return points


def truth_document(plan: FloorPlan, guids: Mapping[str, str]) -> dict:
    """The ``<name>.truth.json`` document."""
    return {
        "model": plan.name,
        "storeys": [{"name": STOREY_NAME, "elevation": STOREY_ELEVATION, "height": STOREY_HEIGHT}],
        "features": [_feature_json(f) for f in truth_features(plan, guids)],
        "free_points": [list(p) for p in free_points(plan)],
        "wall_points": [list(p) for p in wall_points(plan)],
        "corridor_length_m": plan.corridor_length,
        "wall_thickness_m": WALL_THICKNESS,
    }


def _feature_json(f: Feature) -> dict:
    return {
        "ID": f.id,
        "Category": f.category,
        "X": f.x,
        "Y": f.y,
        "Norm_X": f.norm_x,
        "Norm_Y": f.norm_y,
        "Width": f.width,
        "Height": f.height,
        "Storey": f.storey,
        "Elevation": f.elevation,
        "IfcClass": f.ifc_class,
        "Name": f.name,
    }


# --------------------------------------------------------------------------------------------
# Plan-building helpers
# --------------------------------------------------------------------------------------------

DOOR_SIZES: dict[str, Vec] = {
    "room": (0.9, 2.1),
    "gate": (1.0, 2.1),
    "lift": (1.1, 2.1),
    "stair": (1.2, 2.1),
    "exit": (1.2, 2.1),
}
