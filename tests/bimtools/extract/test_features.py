"""Lift evidence: a lift space is a shaft only when shaft-sized; exterior doors enter nothing; a
stair foot faces open floor."""

from __future__ import annotations

import ifcopenshell
import numpy as np
import pytest
from shapely.geometry import box

from bimtools.extract.circulation import FreeRegions, SideProbe, SpaceIndex
from bimtools.extract.features import (
    BodyCandidate,
    DoorCandidate,
    StoreyContext,
    is_shaft_space,
    storey_features,
)
from bimtools.extract.placement import Opening
from bimtools.ifc.categories import load_categories
from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid


def _category(name: str):
    return next(c for c in load_categories().categories if c.name == name)


def test_a_big_space_named_elevator_is_no_shaft():
    lift = _category("Lift")
    assert lift.is_space("Elevator (N.I.C.)")
    assert is_shaft_space(lift, 5.0)
    assert not is_shaft_space(lift, 40.0)  # a lobby-sized "Elevator (N.I.C.)" placeholder
    assert is_shaft_space(_category("Stairs"), 40.0)  # staircases are not bounded by this rule


def test_outside_is_not_reachable():
    assert not SideProbe(label=0, space="", point=(0.0, 0.0)).reachable
    assert SideProbe(label=0, space="Lift", point=(0.0, 0.0), space_index=2, space_area=4.0).reachable
    assert SideProbe(label=5, space="", point=(0.0, 0.0)).reachable


def _context(grid: OccupancyGrid) -> StoreyContext:
    return StoreyContext("Level 0", 0.0, FreeRegions(grid), SpaceIndex([], []), load_categories())


def _flight(guid: str, name: str, foot_x: float, climb: float, steps: int, y: tuple[float, float]):
    """A straight stair along x, its foot at ``foot_x``, rising 0.15 m per 0.3 m step towards
    ``climb`` (+1 or -1), between ``y``, as a stair body (its treads as points)."""
    xs = [foot_x + climb * 0.3 * k for k in range(steps)]
    return BodyCandidate(
        guid=guid,
        ifc_class="IfcStair",
        name=name,
        category="Stairs",
        footprint=box(min(xs), y[0], max(xs), y[1]),
        points=np.array([[(xs[0] + xs[-1]) / 2.0, (y[0] + y[1]) / 2.0]]),
        parts=[np.array([[x, side, 0.15 * k] for k, x in enumerate(xs) for side in y])],
    )


def _stair_storey(wall: tuple[float, float] | None) -> tuple[StoreyContext, BodyCandidate]:
    """A 6 x 3 m floor (0.05 m cells), walled round, with a wall across it from x = ``wall[0]``
    to ``wall[1]`` (none: open), and a straight flight climbing +x from x = 1.0 at y 1-2 (its foot
    faces -x, towards that wall)."""
    res = 0.05
    cells = np.full((60, 120), FREE, dtype=np.uint8)
    if wall is not None:
        cells[:, round(wall[0] / res) : round(wall[1] / res)] = OCCUPIED
    cells[[0, -1], :] = OCCUPIED
    cells[:, [0, -1]] = OCCUPIED
    grid = OccupancyGrid(cells, res, (0.0, 0.0, 0.0))
    return _context(grid), _flight("stair-guid", "Stair 1", 1.0, +1, 12, (1.0, 2.0))


def test_a_stair_foot_facing_open_floor_is_a_feature():
    ctx, body = _stair_storey(None)
    (feature,) = storey_features(ctx, [], [body])
    assert (feature.category, feature.x, feature.y) == ("Stairs", pytest.approx(1.0), pytest.approx(1.5))
    assert (feature.norm_x, feature.norm_y) == (pytest.approx(-1.0), pytest.approx(0.0))
    assert ctx.warnings == []


@pytest.mark.parametrize("wall", [(0.5, 0.8), (0.75, 1.0), (0.8, 0.95)])
def test_a_stair_foot_facing_a_wall_is_skipped_with_a_warning(wall: tuple[float, float]):
    # a wall 0.2-0.5 m in front of the foot, or right at it and thinner than 0.35 m, free floor
    # beyond it: the probe finds the room behind, but the floor in front of the foot is not free
    ctx, body = _stair_storey(wall)
    assert storey_features(ctx, [], [body]) == []
    assert ctx.warnings == ["storey 'Level 0': stair 'Stair 1' (stair-guid): its foot faces a wall, skipped"]


def test_a_stair_foot_outside_the_building_is_skipped_with_a_warning():
    ctx, body = _stair_storey((0.0, 0.8))  # nothing but wall and the map's edge in front of the foot
    assert storey_features(ctx, [], [body]) == []
    assert ctx.warnings == [
        "storey 'Level 0': stair 'Stair 1' (stair-guid): its foot is outside the building, skipped"
    ]


_MODEL = ifcopenshell.file(schema="IFC4")  # outlives the entities made in it (else they dangle)


def _hall_with_a_stair(door_x: float) -> tuple[StoreyContext, DoorCandidate, BodyCandidate]:
    """A 12 x 3 m corridor (y 0-3) and beside it a 10 x 1.8 m hall (y 3.2-5.0, x 0-10) holding a
    stair at its west end (x 0.4-2.5, climbing -x: its foot at x 2.5 faces along the hall), and
    one closed door between them at ``door_x``."""
    res = 0.05
    cells = np.full((110, 250), FREE, dtype=np.uint8)  # 12.5 x 5.5 m, origin (-0.25, -0.25)
    grid = OccupancyGrid(cells, res, (-0.25, -0.25, 0.0))

    def wall(x0: float, x1: float, y0: float, y1: float) -> None:
        (r1, c0), (r0, c1) = (grid.world_to_cell(x, y) for x, y in ((x0, y0), (x1, y1)))
        cells[int(r0) : int(r1) + 1, int(c0) : int(c1) + 1] = OCCUPIED

    for x0, x1, y0, y1 in [(-0.25, 12.2, -0.25, 0), (-0.25, 12.2, 5.0, 5.2), (-0.25, 0, -0.25, 5.2)]:
        wall(x0, x1, y0, y1)
    wall(12.0, 12.2, -0.25, 5.2)
    wall(10.0, 12.0, 3.0, 5.0)  # the corridor's end: no hall beyond x 10
    wall(0.0, 10.0, 3.0, 3.2)  # the wall between, the door closed in it (an obstacle on the map)
    entity = _MODEL.createIfcDoor(GlobalId="door-guid", Name="Glass double door")
    opening = Opening(
        centre=np.array([door_x, 3.1]),
        along=np.array([1.0, 0.0]),
        across=np.array([0.0, 1.0]),
        width=1.0,
        depth=0.2,
        height=2.1,
        floor_z=0.0,
    )
    door = DoorCandidate("door-guid", "IfcDoor", "Glass double door", opening, entity)
    return _context(grid), door, _flight("stair-guid", "Stair 1", 2.5, -1, 8, (3.4, 4.8))


def test_a_door_into_a_small_hall_near_its_stair_enters_the_stair():
    ctx, door, stair = _hall_with_a_stair(door_x=3.5)  # 1 m from the stair
    (feature,) = storey_features(ctx, [door], [stair])
    assert (feature.id, feature.category) == ("door-guid", "Stairs")
    assert feature.norm_y == pytest.approx(-1.0)  # seen from the corridor


def test_a_door_into_a_small_hall_far_from_its_stair_stays_a_door():
    ctx, door, stair = _hall_with_a_stair(door_x=9.0)  # 6.5 m from the stair, at the hall's other end
    features = {f.id: f for f in storey_features(ctx, [door], [stair])}
    assert features["door-guid"].category == "Door"
    assert features["stair-guid"].category == "Stairs"  # the stair's own foot instead
    assert features["stair-guid"].norm_x == pytest.approx(1.0)


def test_a_second_stair_in_the_hall_far_from_the_entrance_gets_its_own_foot():
    ctx, door, stair = _hall_with_a_stair(door_x=3.5)  # the entrance 1 m from the first stair
    second = _flight("second-guid", "Stair 2", 9.0, +1, 4, (3.4, 4.8))  # x 9-9.9: 5.5 m from the entrance
    features = {f.id: f for f in storey_features(ctx, [door], [stair, second])}
    assert set(features) == {"door-guid", "second-guid"}
    assert features["door-guid"].category == features["second-guid"].category == "Stairs"
    assert features["second-guid"].norm_x == pytest.approx(-1.0)
