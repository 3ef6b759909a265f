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
    "PLANS",
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
    "block_a",
    "block_b",
    "check_plan",
    "free_points",
    "host_wall",
    "ntu_hallway",
    "plan",
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


def _r(value: float) -> float:
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
        return (_r((self.x0 + self.x1) / 2), _r((self.y0 + self.y1) / 2))

    @property
    def size(self) -> Vec:
        return (_r(self.x1 - self.x0), _r(self.y1 - self.y0))

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
        return (_r(self.x + half * self.normal[0]), _r(self.y + half * self.normal[1]))


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
        return _r(self.risers * self.going)

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
        return _r(self.hi - self.lo)

    def point(self, t: float) -> Vec:
        """The centre-line point at distance ``t`` from ``lo``."""
        s = _r(self.lo + t)
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
        return _r(sum(c.long_length for c in self.cells if c.kind == "corridor"))

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
    cuts = sorted({_r(v) for e in edges for v in (e.lo, e.hi)})
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
            by_line.setdefault(_r(edge.coord), []).append(edge)
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
                candidates.append((_r(cx + t), cy) if w >= h else (cx, _r(cy + t)))
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


class _DoorMaker:
    """Creates doors on a side of a cell with sequential tags D001, D002, ..."""

    def __init__(self, cells: Iterable[Cell]) -> None:
        self.cells = {c.name: c for c in cells}
        self.doors: list[DoorSpec] = []

    def into(self, cell_name: str, side: Side, at: float, role: DoorRole, name: str = "Door") -> str:
        """A door in side ``side`` of an enclosed cell, ``at`` = its x (N/S sides) or y (E/W sides)."""
        cell = self.cells[cell_name]
        line = {"N": cell.y1, "S": cell.y0, "E": cell.x1, "W": cell.x0}[side]
        return self._add(role, name, side, at, line, cell_name, SIDE_NORMAL[side])

    def exit(self, corridor: str, side: Side, at: float, name: str = "Exit door") -> str:
        """A door in the exterior wall at the end of a corridor; its normal points into the corridor."""
        cell = self.cells[corridor]
        line = {"N": cell.y1, "S": cell.y0, "E": cell.x1, "W": cell.x0}[side]
        nx, ny = SIDE_NORMAL[side]
        return self._add("exit", name, side, at, line, "", (-nx, -ny))

    def _add(
        self,
        role: DoorRole,
        name: str,
        side: Side,
        at: float,
        line: float,
        leads_to: str,
        normal: tuple[int, int],
    ) -> str:
        x, y = (at, line) if side in ("N", "S") else (line, at)
        width, height = DOOR_SIZES[role]
        tag = f"D{len(self.doors) + 1:03d}"
        self.doors.append(DoorSpec(name, role, _r(x), _r(y), normal, width, height, leads_to, tag))
        return tag


def _row(kind: CellKind, names: list[str], xs: list[float], y0: float, y1: float, long: str) -> list[Cell]:
    """Cells side by side along x between consecutive breakpoints ``xs``."""
    spans = zip(names, xs[:-1], xs[1:], strict=True)
    return [Cell(n, kind, a, y0, b, y1, f"{long} {n.split()[-1]}") for n, a, b in spans]


def _units(first: int, count: int) -> list[str]:
    return [f"Unit {i:02d}" for i in range(first, first + count)]


# --------------------------------------------------------------------------------------------
# ntu_hallway: two parallel 84 m corridors, three 7 m links, 38 doors, 5 lifts, no spaces
# --------------------------------------------------------------------------------------------


def ntu_hallway() -> FloorPlan:
    """University hallway: corridors S (y 9-11) and N (y 18-20), x 0-84, links W/M/E between them.

    Rooms line the outer sides (10.5 m wide) and the band between the corridors; a bank of four
    lifts faces the middle link, a fifth lift the east link. Corridor length 2*84 + 3*7 = 189 m.
    """
    length, s_corr, n_corr, band = 84.0, (9.0, 11.0), (18.0, 20.0), (11.0, 18.0)
    cells = [
        Cell("Corridor S", "corridor", 0.0, s_corr[0], length, s_corr[1], "South corridor"),
        Cell("Corridor N", "corridor", 0.0, n_corr[0], length, n_corr[1], "North corridor"),
        Cell("Link W", "corridor", 6.0, band[0], 8.0, band[1], "West link corridor"),
        Cell("Link M", "corridor", 41.0, band[0], 43.0, band[1], "Middle link corridor"),
        Cell("Link E", "corridor", 76.0, band[0], 78.0, band[1], "East link corridor"),
    ]
    outer = [round(10.5 * i, 6) for i in range(9)]
    cells += _row("room", [f"Room S{i}" for i in range(1, 9)], outer, 0.0, s_corr[0], "Lecture room")
    cells += _row("room", [f"Room N{i}" for i in range(1, 9)], outer, n_corr[1], 29.0, "Lecture room")
    inner_w = [0.0, 6.0]
    inner = [8.0, 18.5, 28.5, 38.5]
    inner_e = [45.5, 55.0, 64.5, 73.5]
    cells += _row("room", ["Lab W0"], inner_w, *band, "Laboratory")
    cells += _row("room", ["Lab W1", "Lab W2", "Lab W3"], inner, *band, "Laboratory")
    cells += _row("room", ["Lab E1", "Lab E2", "Lab E3"], inner_e, *band, "Laboratory")
    cells += _row("room", ["Lab E4"], [78.0, 84.0], *band, "Laboratory")
    cells += [
        Cell("Lift 1", "lift_shaft", 38.5, 11.0, 41.0, 14.5, "Lift shaft 1"),
        Cell("Lift 2", "lift_shaft", 38.5, 14.5, 41.0, 18.0, "Lift shaft 2"),
        Cell("Lift 3", "lift_shaft", 43.0, 11.0, 45.5, 14.5, "Lift shaft 3"),
        Cell("Lift 4", "lift_shaft", 43.0, 14.5, 45.5, 18.0, "Lift shaft 4"),
        Cell("Store", "room", 73.5, 11.0, 76.0, 14.5, "Store"),
        Cell("Lift 5", "lift_shaft", 73.5, 14.5, 76.0, 18.0, "Lift shaft 5"),
    ]
    d = _DoorMaker(cells)
    for i in range(1, 9):
        south, north = d.cells[f"Room S{i}"], d.cells[f"Room N{i}"]
        d.into(south.name, "N", south.centre[0], "room")
        d.into(north.name, "S", north.x0 + 7.0, "room")
    for lab in ("Lab W0", "Lab W1", "Lab W2", "Lab W3", "Lab E1", "Lab E2", "Lab E3", "Lab E4"):
        d.into(lab, "S", d.cells[lab].centre[0], "room")
        d.into(lab, "N", d.cells[lab].centre[0], "room")
    for corridor in ("Corridor S", "Corridor N"):
        mid_y = d.cells[corridor].centre[1]
        d.exit(corridor, "W", mid_y)
        d.exit(corridor, "E", mid_y)
    d.into("Store", "E", 12.75, "room")
    d.into("Lab E4", "W", 14.5, "room")
    lifts = []
    landing_sides: list[tuple[int, Side]] = [(1, "E"), (2, "E"), (3, "W"), (4, "W"), (5, "E")]
    for n, side in landing_sides:
        shaft = d.cells[f"Lift {n}"]
        tag = d.into(shaft.name, side, shaft.centre[1], "lift", f"Lift {n} landing door")
        lifts.append(LiftSpec(f"Lift {n}", shaft.name, tag))
    return FloorPlan(
        name="ntu_hallway",
        title="NTU hallway",
        building="University teaching block",
        cells=tuple(cells),
        doors=tuple(d.doors),
        lifts=tuple(lifts),
        with_spaces=False,
        description="Two parallel corridors joined by three links; 38 doors, 5 lifts",
    )


# --------------------------------------------------------------------------------------------
# Residential core: 3 lifts and 2 staircases around a lift lobby
# --------------------------------------------------------------------------------------------


def _block_a_core(d: _DoorMaker) -> tuple[list[LiftSpec], list[StairSpec]]:
    """Lobby x 23.9-37.4, y 6.5-10 off the corridor; stairs and lifts south of it, doors facing north."""
    lifts, stairs = [], []
    for n in (1, 2, 3):
        shaft = d.cells[f"Lift {n}"]
        tag = d.into(shaft.name, "N", shaft.centre[0], "lift", f"Lift {n} landing door")
        lifts.append(LiftSpec(f"Lift {n}", shaft.name, tag))
    for n in (1, 2):
        box = d.cells[f"Stair {n}"]
        d.into(box.name, "N", box.centre[0], "stair")
        stairs.append(StairSpec(f"Stair {n}", box.name, (box.centre[0], 4.9), (0, -1), 1.2, 16, 0.28))
    return lifts, stairs


def block_a() -> FloorPlan:
    """Residential floor, 61.3 m straight corridor (y 10-12) with the lift lobby in the middle.

    Seven units north of the corridor, six south; the core (lobby, Stair 1, Lifts 1-3, Stair 2)
    sits south of the corridor's middle, with a recess in the facade behind the lifts.
    """
    length = 61.3
    cells = [
        Cell("Corridor", "corridor", 0.0, 10.0, length, 12.0, "Common corridor"),
        Cell("Lift Lobby", "lobby", 23.9, 6.5, 37.4, 10.0, "Lift Lobby"),
        Cell("Stair 1", "stair_enclosure", 23.9, 0.0, 26.9, 6.5, "Staircase 1"),
        Cell("Lift 1", "lift_shaft", 26.9, 3.9, 29.4, 6.5, "Lift shaft 1"),
        Cell("Lift 2", "lift_shaft", 29.4, 3.9, 31.9, 6.5, "Lift shaft 2"),
        Cell("Lift 3", "lift_shaft", 31.9, 3.9, 34.4, 6.5, "Lift shaft 3"),
        Cell("Stair 2", "stair_enclosure", 34.4, 0.0, 37.4, 6.5, "Staircase 2"),
    ]
    north_xs = [0.0, 8.75, 17.5, 26.25, 35.0, 43.75, 52.5, length]
    south_units = _units(8, 6)
    cells += _row("unit", _units(1, 7), north_xs, 12.0, 22.0, "Apartment")
    cells += _row("unit", south_units[:3], [0.0, 8.0, 16.0, 23.9], 0.0, 10.0, "Apartment")
    cells += _row("unit", south_units[3:], [37.4, 45.3, 53.3, length], 0.0, 10.0, "Apartment")
    d = _DoorMaker(cells)
    # Gates alternate sides ~4.5 m apart along the corridor (x 2.5 ... 59.0).
    gates = {"Unit 08": 2.5, "Unit 01": 7.0, "Unit 09": 11.5, "Unit 02": 16.0, "Unit 10": 20.5}
    gates |= {"Unit 03": 25.0, "Unit 04": 30.5, "Unit 05": 36.5, "Unit 11": 40.5, "Unit 06": 45.5}
    gates |= {"Unit 12": 50.0, "Unit 07": 54.5, "Unit 13": 59.0}
    for unit in sorted(gates):
        side: Side = "S" if d.cells[unit].y0 >= 12.0 else "N"
        d.into(unit, side, gates[unit], "gate", f"{unit} main gate")
    lifts, stairs = _block_a_core(d)
    return FloorPlan(
        name="block_a",
        title="Residential Block A",
        building="Block A",
        cells=tuple(cells),
        doors=tuple(d.doors),
        lifts=tuple(lifts),
        stairs=tuple(stairs),
        with_spaces=True,
        description="Straight 61.3 m corridor, lift lobby in the middle; 13 units, 3 lifts, 2 stairs",
    )


def block_b() -> FloorPlan:
    """Residential floor with an L-shaped corridor (42.8 m + 20.0 m = 62.8 m) and the lobby at its west end.

    Corridor A runs east (y 10-12, x 8.5-51.3) from the lobby, corridor B turns north (x 49.3-51.3,
    y 12-32). The core west of corridor A: Lifts 1-3 face the lobby from the west, Stair 1 and
    Stair 2 close it to the north and south.
    """
    cells = [
        Cell("Corridor A", "corridor", 8.5, 10.0, 51.3, 12.0, "Common corridor A"),
        Cell("Corridor B", "corridor", 49.3, 12.0, 51.3, 32.0, "Common corridor B"),
        Cell("Lift Lobby", "lobby", 2.5, 7.0, 8.5, 14.5, "Lift Lobby"),
        Cell("Lift 1", "lift_shaft", 0.0, 7.0, 2.5, 9.5, "Lift shaft 1"),
        Cell("Lift 2", "lift_shaft", 0.0, 9.5, 2.5, 12.0, "Lift shaft 2"),
        Cell("Lift 3", "lift_shaft", 0.0, 12.0, 2.5, 14.5, "Lift shaft 3"),
        Cell("Stair 1", "stair_enclosure", 0.0, 14.5, 8.5, 17.5, "Staircase 1"),
        Cell("Stair 2", "stair_enclosure", 0.0, 4.0, 8.5, 7.0, "Staircase 2"),
    ]
    cells += _row("unit", _units(1, 4), [8.5, 19.2, 29.9, 40.6, 51.3], 0.0, 10.0, "Apartment")
    cells += _row("unit", _units(5, 1), [51.3, 61.3], 0.0, 12.0, "Apartment")
    cells += _row("unit", _units(6, 5), [8.5, 16.66, 24.82, 32.98, 41.14, 49.3], 12.0, 22.0, "Apartment")
    cells += [
        Cell("Unit 11", "unit", 51.3, 12.0, 61.3, 22.0, "Apartment 11"),
        Cell("Unit 12", "unit", 39.3, 22.0, 49.3, 32.0, "Apartment 12"),
        Cell("Unit 13", "unit", 51.3, 22.0, 61.3, 32.0, "Apartment 13"),
    ]
    d = _DoorMaker(cells)
    # Gates ~4.5 m apart along corridor A, then ~5-8 m apart along corridor B.
    gates: list[tuple[str, Side, float]] = [
        ("Unit 01", "N", 15.5),
        ("Unit 02", "N", 24.5),
        ("Unit 03", "N", 33.5),
        ("Unit 04", "N", 42.5),
        ("Unit 05", "W", 11.0),
        ("Unit 06", "S", 11.0),
        ("Unit 07", "S", 20.0),
        ("Unit 08", "S", 29.0),
        ("Unit 09", "S", 38.0),
        ("Unit 10", "S", 47.0),
        ("Unit 11", "W", 16.0),
        ("Unit 12", "E", 24.5),
        ("Unit 13", "W", 29.0),
    ]
    for unit, side, at in gates:
        d.into(unit, side, at, "gate", f"{unit} main gate")
    lifts = []
    for n in (1, 2, 3):
        shaft = d.cells[f"Lift {n}"]
        tag = d.into(shaft.name, "E", shaft.centre[1], "lift", f"Lift {n} landing door")
        lifts.append(LiftSpec(f"Lift {n}", shaft.name, tag))
    d.into("Stair 1", "S", 5.5, "stair")
    d.into("Stair 2", "N", 5.5, "stair")
    stairs = [
        StairSpec("Stair 1", "Stair 1", (4.6, 16.4), (-1, 0), 1.2, 16, 0.27),
        StairSpec("Stair 2", "Stair 2", (4.6, 5.1), (-1, 0), 1.2, 16, 0.27),
    ]
    return FloorPlan(
        name="block_b",
        title="Residential Block B",
        building="Block B",
        cells=tuple(cells),
        doors=tuple(d.doors),
        lifts=tuple(lifts),
        stairs=tuple(stairs),
        with_spaces=True,
        description="L-shaped 62.8 m corridor, lift lobby at the west end; 13 units, 3 lifts, 2 stairs",
    )


PLANS = {"ntu_hallway": ntu_hallway, "block_a": block_a, "block_b": block_b}


def plan(name: str) -> FloorPlan:
    """The floor plan of a sample model by name."""
    try:
        return PLANS[name]()
    except KeyError:
        raise KeyError(f"unknown sample model {name!r}; choose from {', '.join(PLANS)}") from None
