"""The three sample floors, drawn as :class:`~bimtools.samples.layouts.FloorPlan` cells, doors,
lifts and stairs (no IFC here), and the helpers that draw them: a door maker with sequential tags,
rows of cells, unit names."""

from __future__ import annotations

from collections.abc import Iterable

from bimtools.samples.layouts import (
    DOOR_SIZES,
    SIDE_NORMAL,
    Cell,
    CellKind,
    DoorRole,
    DoorSpec,
    FloorPlan,
    LiftSpec,
    Side,
    StairSpec,
    round_um,
)

__all__ = [
    "DoorMaker",
    "PLANS",
    "block_a",
    "block_b",
    "cell_row",
    "ntu_hallway",
    "plan",
    "unit_names",
]


class DoorMaker:
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
        self.doors.append(
            DoorSpec(name, role, round_um(x), round_um(y), normal, width, height, leads_to, tag)
        )
        return tag


def cell_row(
    kind: CellKind, names: list[str], xs: list[float], y0: float, y1: float, long: str
) -> list[Cell]:
    """Cells side by side along x between consecutive breakpoints ``xs``."""
    spans = zip(names, xs[:-1], xs[1:], strict=True)
    return [Cell(n, kind, a, y0, b, y1, f"{long} {n.split()[-1]}") for n, a, b in spans]


def unit_names(first: int, count: int) -> list[str]:
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
    cells += cell_row("room", [f"Room S{i}" for i in range(1, 9)], outer, 0.0, s_corr[0], "Lecture room")
    cells += cell_row("room", [f"Room N{i}" for i in range(1, 9)], outer, n_corr[1], 29.0, "Lecture room")
    inner_w = [0.0, 6.0]
    inner = [8.0, 18.5, 28.5, 38.5]
    inner_e = [45.5, 55.0, 64.5, 73.5]
    cells += cell_row("room", ["Lab W0"], inner_w, *band, "Laboratory")
    cells += cell_row("room", ["Lab W1", "Lab W2", "Lab W3"], inner, *band, "Laboratory")
    cells += cell_row("room", ["Lab E1", "Lab E2", "Lab E3"], inner_e, *band, "Laboratory")
    cells += cell_row("room", ["Lab E4"], [78.0, 84.0], *band, "Laboratory")
    cells += [
        Cell("Lift 1", "lift_shaft", 38.5, 11.0, 41.0, 14.5, "Lift shaft 1"),
        Cell("Lift 2", "lift_shaft", 38.5, 14.5, 41.0, 18.0, "Lift shaft 2"),
        Cell("Lift 3", "lift_shaft", 43.0, 11.0, 45.5, 14.5, "Lift shaft 3"),
        Cell("Lift 4", "lift_shaft", 43.0, 14.5, 45.5, 18.0, "Lift shaft 4"),
        Cell("Store", "room", 73.5, 11.0, 76.0, 14.5, "Store"),
        Cell("Lift 5", "lift_shaft", 73.5, 14.5, 76.0, 18.0, "Lift shaft 5"),
    ]
    d = DoorMaker(cells)
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


def _block_a_core(d: DoorMaker) -> tuple[list[LiftSpec], list[StairSpec]]:
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
    south_units = unit_names(8, 6)
    cells += cell_row("unit", unit_names(1, 7), north_xs, 12.0, 22.0, "Apartment")
    cells += cell_row("unit", south_units[:3], [0.0, 8.0, 16.0, 23.9], 0.0, 10.0, "Apartment")
    cells += cell_row("unit", south_units[3:], [37.4, 45.3, 53.3, length], 0.0, 10.0, "Apartment")
    d = DoorMaker(cells)
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
    cells += cell_row("unit", unit_names(1, 4), [8.5, 19.2, 29.9, 40.6, 51.3], 0.0, 10.0, "Apartment")
    cells += cell_row("unit", unit_names(5, 1), [51.3, 61.3], 0.0, 12.0, "Apartment")
    cells += cell_row(
        "unit", unit_names(6, 5), [8.5, 16.66, 24.82, 32.98, 41.14, 49.3], 12.0, 22.0, "Apartment"
    )
    cells += [
        Cell("Unit 11", "unit", 51.3, 12.0, 61.3, 22.0, "Apartment 11"),
        Cell("Unit 12", "unit", 39.3, 22.0, 49.3, 32.0, "Apartment 12"),
        Cell("Unit 13", "unit", 51.3, 22.0, 61.3, 32.0, "Apartment 13"),
    ]
    d = DoorMaker(cells)
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
