"""bimtools.extract.placement: door faces, stair feet and shaft fronts from generated geometry."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from shapely.geometry import box

from bimtools.extract.placement import (
    MAX_FACE_OFFSET,
    heading_deg,
    opening_in_plan,
    rectangle_fronts,
    stair_foot,
)


def _box_verts(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> np.ndarray:
    return np.array(list(itertools.product((x0, x1), (y0, y1), (z0, z1))), dtype=float)


def test_opening_in_plan_from_placement_axes() -> None:
    verts = _box_verts(2.0, 2.9, 5.0, 5.2, 0.0, 2.1)
    door = opening_in_plan(verts, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), None, None)
    np.testing.assert_allclose(door.centre, [2.45, 5.1], atol=1e-12)
    np.testing.assert_allclose(door.along, [1, 0])
    np.testing.assert_allclose(door.across, [0, 1])
    assert door.width == pytest.approx(0.9)
    assert door.depth == pytest.approx(0.2)
    assert door.height == pytest.approx(2.1)
    assert door.floor_z == 0.0
    np.testing.assert_allclose(door.face(+1), [2.45, 5.2])
    np.testing.assert_allclose(door.face(-1), [2.45, 5.0])


def test_opening_follows_the_placement_y_and_caps_the_face_offset() -> None:
    verts = _box_verts(0.0, 1.0, 0.0, 1.0, 0.5, 2.5)  # a 1 m deep element
    door = opening_in_plan(verts, np.array([1.0, 0, 0]), np.array([0, -1.0, 0]), 0.8, 2.0)
    np.testing.assert_allclose(door.across, [0, -1])
    assert door.width == 0.8 and door.height == 2.0  # given quantities win over the mesh
    np.testing.assert_allclose(door.face(+1), [0.5, 0.5 - MAX_FACE_OFFSET])


def test_opening_with_a_vertical_x_axis_uses_the_long_side() -> None:
    verts = _box_verts(0.0, 0.2, 0.0, 1.2, 0.0, 2.0)  # long along y
    door = opening_in_plan(verts, np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), None, None)
    assert abs(door.along[1]) == pytest.approx(1.0)
    np.testing.assert_allclose(door.across, [1, 0], atol=1e-12)
    assert door.width == pytest.approx(1.2)
    assert door.depth == pytest.approx(0.2)


def test_a_door_deeper_than_wide_along_its_placement_x_is_turned() -> None:
    # a Vectorworks export: identity placement, the shape in world coordinates, the wall along y
    verts = _box_verts(11.885, 12.085, 5.927, 6.887, 0.0, 2.13)
    door = opening_in_plan(verts, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), 0.9, 2.1)
    assert abs(door.along[1]) == pytest.approx(1.0)
    assert abs(door.across[0]) == pytest.approx(1.0)
    assert door.depth == pytest.approx(0.2)
    np.testing.assert_allclose(door.centre, [11.985, 6.407], atol=1e-9)
    # with no nominal width, plainly deeper than wide is enough
    door = opening_in_plan(verts, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), None, None)
    assert abs(door.along[1]) == pytest.approx(1.0)


def test_a_door_drawn_open_keeps_its_placement() -> None:
    # frame 1.0 m along x, the leaf open at 90 degrees: 0.95 m deep
    verts = np.vstack(
        [_box_verts(0.0, 1.0, 0.0, 0.15, 0.0, 2.1), _box_verts(0.05, 0.1, 0.15, 0.95, 0.0, 2.1)]
    )
    door = opening_in_plan(verts, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), 0.9, 2.1)
    np.testing.assert_allclose(door.along, [1, 0])


def test_stair_foot_is_the_low_edge_facing_against_the_climb() -> None:
    # a flight climbing +x from x=1 to x=4, 1.2 m wide, rising 1.5 m: treads as points
    steps = []
    for k in range(11):
        x = 1.0 + 0.3 * k
        z = 0.15 * k
        steps += [[x, 0.0, z], [x, 1.2, z]]
    upper = np.array([[0.0, 0.0, 5.0], [0.0, 1.0, 6.0]])  # a higher flight is ignored
    front = stair_foot([np.array(steps), upper, np.zeros((0, 3))])
    assert front is not None
    np.testing.assert_allclose(front.normal, [-1, 0], atol=1e-12)
    np.testing.assert_allclose(front.point, [1.0, 0.6], atol=1e-9)
    assert front.width == pytest.approx(1.2)
    assert front.height == pytest.approx(1.5)


def test_stair_foot_of_a_turning_stair_in_one_body_follows_its_first_flight() -> None:
    # one body (no flights): up +x from x=1 to x=3.4 at y 0-1 (rising 1.2 m), a landing, then
    # back -x at y 1.2-2.2 to 2.4 m. Its top is beside its foot: the foot faces -x, not -y.
    verts = []
    for k in range(9):
        x, z = 1.0 + 0.3 * k, 0.15 * k
        verts += [[x, 0.0, z], [x, 1.0, z]]
    verts += [[3.4, 0.0, 1.2], [3.4, 2.2, 1.2], [4.4, 0.0, 1.2], [4.4, 2.2, 1.2]]
    for k in range(9):
        x, z = 3.4 - 0.3 * k, 1.2 + 0.15 * k
        verts += [[x, 1.2, z], [x, 2.2, z]]
    front = stair_foot([np.array(verts)])
    assert front is not None
    np.testing.assert_allclose(front.normal, [-1, 0], atol=1e-9)
    np.testing.assert_allclose(front.point, [1.0, 0.5], atol=1e-9)


def test_stair_foot_without_parts_or_climb_is_none() -> None:
    assert stair_foot([]) is None
    flat = _box_verts(0, 1, 0, 1, 0, 0)
    assert stair_foot([flat]) is None


def test_rectangle_fronts_have_outward_normals() -> None:
    fronts = rectangle_fronts(box(0, 0, 2, 1))
    assert len(fronts) == 4
    centre = np.array([1.0, 0.5])
    for f in fronts:
        assert float(f.normal @ (f.point - centre)) > 0
        assert math.hypot(*f.normal) == pytest.approx(1.0)
    assert sorted(round(f.width, 9) for f in fronts) == [1.0, 1.0, 2.0, 2.0]


def test_heading_deg() -> None:
    assert heading_deg(np.array([0.0, 1.0])) == pytest.approx(90.0)
    assert heading_deg(np.array([-1.0, 0.0])) == pytest.approx(180.0)
