"""bimtools.extract.floorplan: the solid, the outline and the wall surfaces of a generated plan."""

from __future__ import annotations

import math

import pytest
from shapely.geometry import Point, Polygon, box

from bimtools.extract.floorplan import (
    ObstacleShape,
    build_floorplan,
    building_outline,
    fill_holes,
    wall_surfaces,
)


def _room(size: float = 4.0, t: float = 0.2) -> list[ObstacleShape]:
    """Four walls of a square room, inner faces at 0 and ``size``."""
    return [
        ObstacleShape("south", "IfcWall", box(-t, -t, size + t, 0.0)),
        ObstacleShape("north", "IfcWall", box(-t, size, size + t, size + t)),
        ObstacleShape("west", "IfcWall", box(-t, 0.0, 0.0, size)),
        ObstacleShape("east", "IfcWall", box(size, 0.0, size + t, size), glass=True),
    ]


def test_fill_holes_keeps_only_exteriors() -> None:
    ring = box(0, 0, 10, 10).difference(box(2, 2, 8, 8))
    assert ring.area == pytest.approx(64.0)
    assert fill_holes(ring).area == pytest.approx(100.0)


def test_building_outline_closes_small_gaps_but_not_wide_ones() -> None:
    left, right = box(0, 0, 1, 1), box(1.5, 0, 2.5, 1)  # 0.5 m gap < 2 x 0.35 m
    closed = building_outline(left.union(right), [])
    assert closed.geom_type == "Polygon"
    assert closed.contains(Point(1.25, 0.5))
    far = box(3.5, 0, 4.5, 1)  # 1.0 m gap stays open
    opened = building_outline(left.union(far), [])
    assert opened.geom_type == "MultiPolygon"
    assert building_outline(Polygon(), []).is_empty


def test_floorplan_of_a_room_has_free_inside_and_inward_wall_normals() -> None:
    plan = build_floorplan("Level 1", 1.0, _room(), spaces=[])
    assert plan.outline.area == pytest.approx(4.4 * 4.4, rel=1e-3)
    assert plan.free.area == pytest.approx(16.0, rel=1e-3)
    assert plan.free.contains(Point(2, 2))
    inner = [w for w in plan.walls if abs(w.length - 4.0) < 1e-3]
    assert len(inner) == 4
    for w in inner:
        mx, my = (w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2
        # normal points from the wall face towards the room centre (2, 2)
        assert w.normal[0] * (2 - mx) + w.normal[1] * (2 - my) > 0
        assert math.hypot(*w.normal) == pytest.approx(1.0)
    owners = {w.element for w in inner}
    assert owners == {"south", "north", "west", "east"}
    assert all(w.glass == (w.element == "east") for w in plan.walls)
    outer = [w for w in plan.walls if abs(w.length - 4.4) < 1e-3]
    assert len(outer) == 4
    for w in outer:
        mx, my = (w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2
        assert w.normal[0] * (mx - 2) + w.normal[1] * (my - 2) > 0  # outwards on the envelope


def test_obstacle_records_split_multipolygons_and_keep_holes() -> None:
    column = ObstacleShape("c", "IfcColumn", box(0, 0, 1, 1).union(box(3, 0, 4, 1)))
    ring = ObstacleShape("r", "IfcWall", box(5, 0, 9, 4).difference(box(6, 1, 8, 3)))
    plan = build_floorplan("L", 1.0, [column, ring], spaces=[])
    records = plan.obstacle_records()
    assert [r.element for r in records].count("c") == 2
    (ring_record,) = [r for r in records if r.element == "r"]
    assert len(ring_record.holes) == 1
    assert all(r.storey == "L" for r in records)


def test_spaces_extend_the_outline_and_empty_plans_have_no_walls() -> None:
    plan = build_floorplan("L", 1.0, [], spaces=[box(0, 0, 5, 3)])
    assert plan.walls == []
    assert plan.outline.area == pytest.approx(15.0)
    assert plan.free.area == pytest.approx(15.0)
    assert wall_surfaces("L", [], Polygon()) == []


def test_collinear_edges_of_one_element_merge_into_one_segment() -> None:
    # a wall drawn as two touching boxes is one element: its long face is one segment
    wall = ObstacleShape("w", "IfcWall", box(0, 0, 3, 0.2).union(box(3, 0, 6, 0.2)))
    plan = build_floorplan("L", 1.0, [wall], spaces=[])
    lengths = sorted(round(w.length, 6) for w in plan.walls)
    assert lengths == [0.2, 0.2, 6.0, 6.0]
