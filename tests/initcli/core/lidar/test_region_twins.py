"""Spaces a lidar cannot tell apart (initcli.core.lidar.region_twins): a motion that lays a free region's
walls on walls and its floor on floor."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

from initcli.core.lidar.region_twins import region_twins

RES = 0.05
ORIGIN = (0.0, 0.0)


def cells(m: float) -> int:
    return round(m / RES)


def floor_plan(
    rooms: list[np.ndarray], at: list[tuple[float, float]], size: tuple[float, float] = (30.0, 12.0)
):
    """Free-space masks ``rooms`` (row 0 the top) placed with their top-left corner at ``at`` (x, y of
    the corner from the map's top-left, m), everything else wall; the labelled map and each room's label."""
    h, w = cells(size[1]), cells(size[0])
    free = np.zeros((h, w), dtype=bool)
    for room, (x, y) in zip(rooms, at, strict=True):
        r, c = cells(y), cells(x)
        free[r : r + room.shape[0], c : c + room.shape[1]] |= room
    labels, _ = ndimage.label(free)
    ids = [
        int(labels[cells(y) + np.argwhere(room)[0][0], cells(x) + np.argwhere(room)[0][1]])
        for room, (x, y) in zip(rooms, at, strict=True)
    ]
    return labels, ids


def rect(w: float, h: float) -> np.ndarray:
    return np.ones((cells(h), cells(w)), dtype=bool)


def ell() -> np.ndarray:
    """A 6 x 5 m room with a 3 x 2 m bite out of one corner: no turn lays it on itself."""
    room = rect(6.0, 5.0)
    room[: cells(2.0), cells(3.0) :] = False
    return room


def twin_of(labels: np.ndarray, label: int):
    found = {t.label: t for t in region_twins(labels, RES, ORIGIN, [label])}
    return found.get(label)


def test_an_l_shaped_room_alone_has_no_twin() -> None:
    labels, (room, other) = floor_plan([ell(), rect(4.0, 3.0)], [(1.0, 1.0), (10.0, 1.0)])
    assert twin_of(labels, room) is None
    assert twin_of(labels, other) is not None  # a rectangle is its own twin turned half round


def test_two_identical_rooms_are_each_others_twins_by_a_shift() -> None:
    labels, (a, b) = floor_plan([ell(), ell()], [(1.0, 1.0), (12.0, 4.0)])
    twin = twin_of(labels, a)
    assert twin is not None and twin.twin == b
    assert abs(twin.turn_deg) < 1.0
    assert (twin.motion.x, twin.motion.y) == pytest.approx((11.0, -3.0), abs=RES)  # y up: 3 m lower


def test_a_room_turned_a_quarter_is_a_twin_a_mirror_image_is_not() -> None:
    turned = np.rot90(ell())  # counter-clockwise in the picture
    labels, (a, b) = floor_plan([ell(), turned], [(1.0, 1.0), (12.0, 1.0)])
    twin = twin_of(labels, a)
    assert twin is not None and twin.twin == b
    assert twin.turn_deg == pytest.approx(90.0, abs=1.0)
    labels, (a, b) = floor_plan([ell(), ell()[:, ::-1]], [(1.0, 1.0), (12.0, 1.0)])
    assert twin_of(labels, a) is None  # a lidar sees handedness


def ring(notch: bool) -> np.ndarray:
    """A ring corridor 2 m wide round a 20 x 4 m block; ``notch``: a recess 0.4 m deep in one side."""
    room = rect(24.0, 8.0)
    room[cells(2.0) : cells(6.0), cells(2.0) : cells(22.0)] = False
    if notch:
        room = np.vstack([np.zeros((cells(0.4), room.shape[1]), dtype=bool), room])
        room[: cells(0.4), cells(5.0) : cells(6.0)] = True
    return room


def test_a_point_symmetric_ring_corridor_is_its_own_twin_turned_half_round() -> None:
    labels, (corridor,) = floor_plan([ring(notch=False)], [(2.0, 2.0)])
    twin = twin_of(labels, corridor)
    assert twin is not None and twin.twin == corridor
    assert abs(twin.turn_deg) == pytest.approx(180.0, abs=1.0)
    # the centre of the turn is the ring's centre: x 2 + 12, y (12 - 2 - 4) m from the bottom
    c, s = math.cos(twin.motion.yaw), math.sin(twin.motion.yaw)
    centre = np.linalg.solve(np.eye(2) - np.array([[c, -s], [s, c]]), [twin.motion.x, twin.motion.y])
    assert centre == pytest.approx([14.0, 6.0], abs=RES)


def test_a_recess_on_one_side_breaks_the_ring_corridor_s_twin() -> None:
    labels, (corridor,) = floor_plan([ring(notch=True)], [(2.0, 1.6)])
    assert twin_of(labels, corridor) is None


def test_unknown_or_empty_regions_are_skipped() -> None:
    labels, (room,) = floor_plan([ell()], [(1.0, 1.0)])
    assert region_twins(labels, RES, ORIGIN, [0, 99]) == []
    assert region_twins(np.zeros((10, 10), dtype=int), RES, ORIGIN, [1]) == []


def test_walls_alike_within_the_tolerance_make_twins_a_deeper_difference_does_not() -> None:
    shallow = rect(6.0, 4.0)
    shallow = np.vstack([np.zeros((cells(0.1), shallow.shape[1]), dtype=bool), shallow])
    shallow[: cells(0.1), cells(1.0) : cells(2.0)] = True  # a recess 0.1 m deep in one long wall
    labels, (room,) = floor_plan([shallow], [(2.0, 2.0)])
    assert twin_of(labels, room) is not None  # within 0.1 m (two cells) of its turned self
    found = {t.label for t in region_twins(labels, RES, ORIGIN, [room], tolerance=0.05)}
    assert room not in found  # a lidar check this fine tells the recess's side


def alcove_square() -> np.ndarray:
    """A 4 x 4 m room with a 1 x 0.5 m alcove off one wall: too round for a principal axis, and no
    turn lays it on itself."""
    room = np.zeros((cells(4.5), cells(4.0)), dtype=bool)
    room[cells(0.5) :, :] = True
    room[: cells(0.5), cells(0.5) : cells(1.5)] = True
    return room


def test_near_square_rooms_alike_are_twins_though_their_axes_mean_nothing() -> None:
    labels, (a, b) = floor_plan([alcove_square(), alcove_square()], [(1.0, 1.0), (12.0, 4.0)])
    twin = twin_of(labels, a)
    assert twin is not None and twin.twin == b
    assert (twin.motion.x, twin.motion.y) == pytest.approx((11.0, -3.0), abs=RES)
    labels, (a, b) = floor_plan([alcove_square(), np.rot90(alcove_square(), -1)], [(1.0, 1.0), (12.0, 4.0)])
    twin = twin_of(labels, a)
    assert twin is not None and twin.twin == b and twin.turn_deg == pytest.approx(-90.0, abs=1.0)


def test_a_column_by_one_room_s_wall_only_breaks_the_twin() -> None:
    with_column = ell()
    r, c = cells(3.0), cells(0.15)  # a column 0.05 m square standing 0.15 m off the west wall
    with_column[r : r + 1, c : c + 1] = False
    labels, (a, b) = floor_plan([ell(), with_column], [(1.0, 1.0), (12.0, 1.0)])
    # at a tolerance of 0.15 m a's walls all land on b's, and a's floor beyond the
    # tolerance from a wall on b's floor; b's column, 0.2 m from a's wall, lands on nothing of a's
    assert region_twins(labels, RES, ORIGIN, [a], tolerance=0.15) == []


def test_the_map_s_edge_bounds_a_room_as_a_wall_does() -> None:
    labels, (a, b) = floor_plan([ell(), ell()], [(0.0, 0.0), (12.0, 4.0)])  # a touches the map's edge
    assert labels[0, 0] == a
    twin = twin_of(labels, a)
    assert twin is not None and twin.twin == b
    back = twin_of(labels, b)
    assert back is not None and back.twin == a


def test_each_region_asked_for_once_as_an_array_or_a_list() -> None:
    labels, (a, b) = floor_plan([ell(), ell()], [(1.0, 1.0), (12.0, 4.0)])
    found = region_twins(labels, RES, ORIGIN, np.array([a, a, b]))
    assert [t.label for t in found] == [a, b]
