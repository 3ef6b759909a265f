"""Circulation side from the plan: corridor shape, door counts, vertical links, never outside."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from bimtools.extract.circulation import (
    FreeRegions,
    PlaceShape,
    SideProbe,
    SpaceIndex,
    choose_side,
    is_circulation_shape,
    probe_side,
    rectangle_equivalent,
)
from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

RES = 0.1


def _grid(free_boxes: list[tuple[float, float, float, float]], size=(30.0, 12.0)) -> OccupancyGrid:
    """A grid of ``size`` metres, free inside the boxes (x0, y0, x1, y1), walls elsewhere inside."""
    rows, cols = int(size[1] / RES), int(size[0] / RES)
    cells = np.full((rows, cols), OCCUPIED, dtype=np.uint8)
    cells[:, :2] = cells[:, -2:] = UNKNOWN
    for x0, y0, x1, y1 in free_boxes:
        r0, r1 = rows - int(round(y1 / RES)), rows - int(round(y0 / RES))
        cells[r0:r1, int(round(x0 / RES)) : int(round(x1 / RES))] = FREE
    return OccupancyGrid(cells=cells, resolution=RES, origin=(0.0, 0.0, 0.0))


def never(_: str) -> bool:
    return False


@pytest.mark.parametrize(
    ("area", "perimeter", "length", "width"),
    [(40.0, 44.0, 20.0, 2.0), (16.0, 16.0, 4.0, 4.0), (12.0, 16.0, 6.0, 2.0)],
)
def test_rectangle_equivalent(area, perimeter, length, width):
    got = rectangle_equivalent(area, perimeter)
    assert got == pytest.approx((length, width), abs=1e-6)


def test_corridor_shape_rules():
    corridor = PlaceShape(width=2.0, length=20.0, doors=4, vertical=False)
    room = PlaceShape(width=4.0, length=5.0, doors=1, vertical=False)
    hall = PlaceShape(width=8.0, length=10.0, doors=3, vertical=True)
    narrow_room = PlaceShape(width=2.0, length=10.0, doors=1, vertical=False)
    assert is_circulation_shape(corridor) and is_circulation_shape(hall)
    assert not is_circulation_shape(room) and not is_circulation_shape(narrow_room)
    assert not is_circulation_shape(PlaceShape(width=8.0, length=10.0, doors=3, vertical=False))


def test_region_width_of_a_strip_and_a_room():
    grid = _grid([(1.0, 1.0, 25.0, 3.0), (5.0, 5.0, 10.0, 10.0)])
    regions = FreeRegions(grid)
    corridor, room = regions.label_at(10.0, 2.0), regions.label_at(7.0, 7.0)
    assert corridor != room and corridor and room
    assert regions.widths[corridor] == pytest.approx(2.0, rel=0.15)
    assert regions.widths[room] > 3.0


def _corridor_and_room(names: tuple[str, str]):
    """A 24 m x 2 m corridor below a 5 m x 5 m room; a door between them at x = 7.5 (faces at y = 3, 4) whose
    leaf is not cut at the section height, so both sides are one free region."""
    grid = _grid([(1.0, 1.0, 25.0, 3.0), (5.0, 4.0, 10.0, 9.0), (7.0, 3.0, 8.0, 4.0)])
    regions = FreeRegions(grid)
    spaces = SpaceIndex(list(names), [shapely.box(1.0, 1.0, 25.0, 3.0), shapely.box(5.0, 4.0, 10.0, 9.0)])
    return regions, spaces


def test_corridor_wins_by_shape_when_its_name_says_nothing():
    # A Revit export names its corridor space "Floor 1": the name rule cannot tell the sides apart.
    regions, spaces = _corridor_and_room(("Floor 1", "Office 101"))
    up = probe_side(regions, spaces, 7.5, 4.0, np.array([0.0, 1.0]))  # into the office
    down = probe_side(regions, spaces, 7.5, 3.0, np.array([0.0, -1.0]))  # into the corridor
    assert up.space == "Office 101" and down.space == "Floor 1"
    assert up.label == down.label  # the free-space test cannot tell them apart either
    spaces.doors[:] = [4, 1]  # the corridor serves four doors, the office one
    assert choose_side(up, down, regions, never, never, spaces) == (-1, "plan")
    assert choose_side(down, up, regions, never, never, spaces) == (1, "plan")


def test_plan_rule_beats_a_misleading_name():
    # The room is named "Hall" (matches the circulation regex) but is a one-door meeting room.
    regions, spaces = _corridor_and_room(("Floor 1", "Lecture Hall"))
    up = probe_side(regions, spaces, 7.5, 4.0, np.array([0.0, 1.0]))
    down = probe_side(regions, spaces, 7.5, 3.0, np.array([0.0, -1.0]))
    spaces.doors[:] = [5, 1]
    side, rule = choose_side(up, down, regions, lambda n: "hall" in n.lower(), never, spaces)
    assert (side, rule) == (-1, "plan")


def test_a_side_outside_the_building_never_wins():
    inside = SideProbe(label=3, space="Treppenhaus", point=(0.0, 0.0), space_index=0, space_area=20.0)
    outside = SideProbe(label=0, space="", point=(0.0, 1.0))
    # Even though the inside is a stair space (which the name rule makes the room side).
    regions = FreeRegions(_grid([(1.0, 1.0, 5.0, 5.0)]))
    is_stair = lambda name: "treppe" in name.lower()  # noqa: E731
    assert choose_side(inside, outside, regions, never, is_stair) == (1, "outside")
    assert choose_side(outside, inside, regions, never, is_stair) == (-1, "outside")
    assert not outside.reachable and inside.reachable
