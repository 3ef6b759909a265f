"""Test worlds beyond the three samples, as plans for the sample IFC writer (issue 31).

- ``crane_hall``: a Revit-like crane hall, a 60 x 18 m hall with workshops, stores, a stair and a
  lift along both long sides (their doors face the hall) and gates in its façade: one 5 m gate
  in the west end and one 6 m gate in the north façade stand open (openings no door fills), an
  exit door closes the east end. No IfcSpace; a floor slab under every cell bounds the building.
- ``open_hall``: a 48 x 16 m hall standing alone, exit doors along both long sides, 5 m gates open
  in both ends; only its floor slab bounds its free space.
- ``house``: a Renga-like house, 12 x 10 m: a 2 m hallway between a living room and a 5 x 6 m
  bedroom, a kitchen and a staircase; every room behind a door; spaces per room.
- ``house_open``: the same house with the bedroom's door left out (an open doorway).
- ``semi_detached``: two 8 x 10 m homes side by side, the east one the west one turned half round
  (a duplex): the storey is the same turned 180 degrees about its centre, walls and doors alike.

:func:`as_built_plan` writes a variant of any plan as built: doors removed (their opening left
free), walled up (no opening at all) or shifted along their wall; :func:`sample_as_built` those of
the three samples (:data:`AS_BUILT_CHANGES`), and :func:`write_plan` writes any plan as IFC.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from pathlib import Path

from bimtools.samples.layouts import Cell, DoorSpec, FloorPlan, LiftSpec, StairSpec, round_um
from bimtools.samples.plans import DoorMaker, cell_row, plan

__all__ = [
    "AS_BUILT_CHANGES",
    "WORLDS",
    "as_built_plan",
    "crane_hall",
    "house",
    "house_open",
    "open_hall",
    "sample_as_built",
    "semi_detached",
    "world",
    "write_plan",
]


def _open(d: DoorMaker, tags: Iterable[str]) -> tuple[tuple[DoorSpec, ...], tuple[DoorSpec, ...]]:
    """The maker's doors with ``tags`` taken out as openings no door fills: (doors, openings)."""
    wanted = set(tags)
    doors = tuple(x for x in d.doors if x.tag not in wanted)
    openings = tuple(
        dataclasses.replace(x, role="exit", name=f"Gate {x.tag}") for x in d.doors if x.tag in wanted
    )
    return doors, openings


def crane_hall() -> FloorPlan:
    """A 60 x 18 m crane hall (y 6-24) between a row of workshops and stores (south, y 0-6) and
    offices, a lift and a gap in the north façade (y 24-30); gates open to the outside."""
    cells = [Cell("Hall", "corridor", 0.0, 6.0, 60.0, 24.0, "Crane hall")]
    cells += cell_row(
        "room",
        ["Workshop 1", "Workshop 2", "Store 1", "Workshop 3", "Store 2"],
        [0.0, 11.0, 20.0, 27.5, 38.0, 47.0],
        0.0,
        6.0,
        "Room",
    )
    cells += [Cell("Stair 1", "stair_enclosure", 47.0, 0.0, 60.0, 6.0, "Staircase 1")]
    cells += cell_row("room", ["Office 1", "Office 2"], [0.0, 9.0, 21.5], 24.0, 30.0, "Office")
    cells += [Cell("Lift 1", "lift_shaft", 21.5, 24.0, 24.0, 26.5, "Lift shaft 1")]
    # x 24-33 of the north façade is the hall's own wall (the north gate), then two more offices
    cells += cell_row("room", ["Office 3", "Office 4"], [33.0, 46.0, 60.0], 24.0, 30.0, "Office")
    d = DoorMaker(cells)
    south = {"Workshop 1": 4.0, "Workshop 2": 16.5, "Store 1": 22.0, "Workshop 3": 31.0, "Store 2": 44.0}
    for name, at in south.items():
        d.into(name, "N", at, "room", f"{name} door")
    d.into("Stair 1", "N", 50.0, "stair", "Stair 1 door")
    for name, at in {"Office 1": 3.0, "Office 2": 13.0, "Office 3": 41.0, "Office 4": 55.5}.items():
        d.into(name, "S", at, "room", f"{name} door")
    lift = d.into("Lift 1", "S", 22.75, "lift", "Lift 1 landing door")
    d.exit("Hall", "E", 12.0, "East exit")
    west = d.exit("Hall", "W", 15.0, "West gate")
    north = d.exit("Hall", "N", 28.5, "North gate")
    # the gates: 5 m and 6 m wide, standing open
    d.doors = [
        dataclasses.replace(x, width=5.0 if x.tag == west else 6.0, height=4.5)
        if x.tag in (west, north)
        else x
        for x in d.doors
    ]
    doors, openings = _open(d, (west, north))
    return FloorPlan(
        name="crane_hall",
        title="Crane hall",
        building="Production hall",
        cells=tuple(cells),
        doors=doors,
        lifts=(LiftSpec("Lift 1", "Lift 1", lift),),
        stairs=(StairSpec("Stair 1", "Stair 1", (50.0, 3.0), (1, 0), 1.2, 16, 0.28),),
        openings=openings,
        with_slab=True,
        description="60 x 18 m hall, doors along both long sides, two gates open in the façade",
    )


def open_hall() -> FloorPlan:
    """A 48 x 16 m hall standing alone (no rooms round it): exit doors along both long sides and
    gates standing open in both end façades. Its whole free space reaches the outside; only the
    floor slab bounds it (bim-extract before slabs: no free space at all)."""
    cells = [Cell("Hall", "corridor", 0.0, 0.0, 48.0, 16.0, "Assembly hall")]
    d = DoorMaker(cells)
    for k, at in enumerate((4.0, 13.5, 21.0, 33.0)):
        d.exit("Hall", "S", at, f"South door {k + 1}")
    for k, at in enumerate((6.0, 17.0, 26.5, 31.0, 42.5)):
        d.exit("Hall", "N", at, f"North door {k + 1}")
    west = d.exit("Hall", "W", 9.0, "West gate")
    east = d.exit("Hall", "E", 10.0, "East gate")
    d.doors = [dataclasses.replace(x, width=5.0, height=4.5) if x.tag in (west, east) else x for x in d.doors]
    doors, openings = _open(d, (west, east))
    return FloorPlan(
        name="open_hall",
        title="Open hall",
        building="Assembly hall",
        cells=tuple(cells),
        doors=doors,
        openings=openings,
        with_slab=True,
        description="48 x 16 m hall alone, doors along both long sides, gates open in both ends",
    )


def _house_cells() -> list[Cell]:
    return [
        Cell("Hallway", "corridor", 5.0, 0.0, 7.0, 10.0, "Hallway"),
        Cell("Living", "room", 0.0, 0.0, 5.0, 6.0, "Living room"),
        Cell("Kitchen", "room", 0.0, 6.0, 5.0, 10.0, "Kitchen"),
        Cell("Bedroom", "room", 7.0, 0.0, 12.0, 6.0, "Bedroom"),
        Cell("Stair 1", "stair_enclosure", 7.0, 6.0, 12.0, 10.0, "Staircase"),
    ]


def house(bedroom_door: bool = True) -> FloorPlan:
    """A 12 x 10 m house: the hallway x 5-7 runs north from the entrance; the bedroom (x 7-12,
    y 0-6: 5 x 6 m) east of it; ``bedroom_door`` False leaves its doorway open."""
    cells = _house_cells()
    d = DoorMaker(cells)
    d.into("Living", "E", 2.0, "room", "Living room door")
    d.into("Kitchen", "E", 8.5, "room", "Kitchen door")
    bedroom = d.into("Bedroom", "W", 4.5, "room", "Bedroom door")
    d.into("Stair 1", "W", 7.5, "stair", "Stair door")
    d.exit("Hallway", "S", 6.0, "Entrance")
    doors, openings = _open(d, () if bedroom_door else (bedroom,))
    return FloorPlan(
        name="house" if bedroom_door else "house_open",
        title="House",
        building="Family house",
        cells=tuple(cells),
        doors=doors,
        stairs=(StairSpec("Stair 1", "Stair 1", (8.0, 8.0), (1, 0), 1.0, 13, 0.26),),
        openings=openings,
        with_spaces=True,
        description="12 x 10 m house, every room behind a door"
        + ("" if bedroom_door else "; the bedroom's doorway open"),
    )


def house_open() -> FloorPlan:
    """:func:`house` with the bedroom's doorway open (no door in it)."""
    return house(bedroom_door=False)


def semi_detached() -> FloorPlan:
    """Two 8 x 10 m homes (a hallway x 3-5 between a living room and kitchen west and a bedroom
    east), the east home the west one turned 180 degrees about (8, 5): point-symmetric."""
    west = [
        ("Hallway", "corridor", 3.0, 0.0, 5.0, 10.0),
        ("Living", "room", 0.0, 0.0, 3.0, 6.0),
        ("Kitchen", "room", 0.0, 6.0, 3.0, 10.0),
        ("Bedroom", "room", 5.0, 0.0, 8.0, 10.0),
    ]
    turned = [(f"{n} East", k, 16.0 - x1, 10.0 - y1, 16.0 - x0, 10.0 - y0) for n, k, x0, y0, x1, y1 in west]
    cells = [Cell(n, k, x0, y0, x1, y1, n) for n, k, x0, y0, x1, y1 in [*west, *turned]]  # type: ignore[arg-type]
    d = DoorMaker(cells)
    d.into("Living", "E", 2.0, "room", "Living room door")
    d.into("Kitchen", "E", 8.5, "room", "Kitchen door")
    d.into("Bedroom", "W", 4.5, "room", "Bedroom door")
    d.exit("Hallway", "S", 4.0, "Entrance")
    d.into("Living East", "W", 10.0 - 2.0, "room", "Living room door")  # the same, turned
    d.into("Kitchen East", "W", 10.0 - 8.5, "room", "Kitchen door")
    d.into("Bedroom East", "E", 10.0 - 4.5, "room", "Bedroom door")
    d.exit("Hallway East", "N", 16.0 - 4.0, "Entrance")
    return FloorPlan(
        name="semi_detached",
        title="Semi-detached houses",
        building="Two homes, one turned half round",
        cells=tuple(cells),
        doors=tuple(d.doors),
        with_spaces=True,
        description="two 8 x 10 m homes, the east one the west one turned 180 degrees (a duplex)",
    )


WORLDS = {
    "crane_hall": crane_hall,
    "open_hall": open_hall,
    "house": house,
    "house_open": house_open,
    "semi_detached": semi_detached,
}


def world(name: str) -> FloorPlan:
    """A test world's plan by name."""
    try:
        return WORLDS[name]()
    except KeyError:
        raise KeyError(f"unknown test world {name!r}; choose from {', '.join(WORLDS)}") from None


def as_built_plan(
    design: FloorPlan,
    removed: Iterable[str] = (),
    walled: Iterable[str] = (),
    shifted: Mapping[str, float] | None = None,
    name: str = "",
) -> FloorPlan:
    """``design`` as built: the doors tagged in ``removed`` never installed (their opening left free),
    those in ``walled`` walled up (no opening), those in ``shifted`` moved that many metres along
    their wall (+: along the door's local X). Lifts keep their landing doors."""
    shifted = dict(shifted or {})
    gone, walls = set(removed), set(walled)
    doors: list[DoorSpec] = []
    openings = list(design.openings)
    for door in design.doors:
        if door.tag in walls:
            continue
        if door.tag in shifted:
            s = shifted[door.tag]
            door = dataclasses.replace(
                door, x=round_um(door.x + s * door.along[0]), y=round_um(door.y + s * door.along[1])
            )
        (openings if door.tag in gone else doors).append(door)
    return dataclasses.replace(
        design,
        name=name or f"{design.name}_as_built",
        doors=tuple(doors),
        openings=tuple(openings),
        description=f"{design.description} (as built: {len(gone)} door(s) removed, {len(walls)} walled up, "
        f"{len(shifted)} shifted)",
    )


# The as-built variants of the samples used for `sim.world: <name>_as_built.ifc`: gates and room
# doors removed (a free doorway), walled up or built 0.4-0.6 m off their place.
AS_BUILT_CHANGES: dict[str, dict[str, object]] = {
    "ntu_hallway": {"removed": ("D003", "D020"), "walled": ("D010",), "shifted": {"D005": 0.5, "D024": -0.4}},
    "block_a": {"removed": ("D004",), "walled": ("D009",), "shifted": {"D002": 0.5, "D011": -0.6}},
    "block_b": {"removed": ("D007",), "walled": ("D003",), "shifted": {"D001": -0.5, "D012": 0.4}},
}


def sample_as_built(name: str) -> FloorPlan:
    """The as-built variant of sample ``name`` (:data:`AS_BUILT_CHANGES`)."""
    c = AS_BUILT_CHANGES[name]
    return as_built_plan(plan(name), **c)  # type: ignore[arg-type]


def write_plan(floor: FloorPlan, out_dir: Path) -> Path:
    """Write ``<out_dir>/<plan name>.ifc`` (the sample writer, byte-identical from run to run)."""
    from bimtools.samples.ifc_writer import write_model

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{floor.name}.ifc"
    path.write_text(write_model(floor).model.to_string(), encoding="utf-8", newline="\n")
    return path
