"""The survey's model of the session's lidar registration (initcli.survey.lidar): a room that is its
own twin turned half round places no start, one with a corner of its own does; a start is placed
once it has driven a whole window, at the first placed point of its loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.lidar.registration import RegistrationMap
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.storey.outlines import polygon_edges
from initcli.survey.exploration import Entry, Loop
from initcli.survey.lidar import LidarModel, LoopRegistration, lidar_distances

RES = 0.05
PARAMS = RegistrationParams(window=10.0, every=2.5)


def _grid(outline: np.ndarray) -> OccupancyGrid:
    """The outline's walls (one cell thick) and the free floor inside, 1 m of margin round it."""
    import cv2

    lo = outline.min(axis=0) - 1.0
    rows, cols = (np.ceil((outline.max(axis=0) - lo + 1.0) / RES)).astype(int)[::-1]
    cells = np.zeros((rows, cols), np.uint8)
    pts = np.round((outline - lo) / RES).astype(np.int32)
    cv2.fillPoly(cells, [pts], 1)
    grid = np.full((rows, cols), UNKNOWN, np.uint8)  # outside
    grid[cells > 0] = FREE
    cv2.polylines(grid, [pts], True, int(OCCUPIED), 1)
    return OccupancyGrid(grid[::-1].copy(), RES, (float(lo[0]), float(lo[1]), 0.0))  # row 0 on top


def _loop(inner: np.ndarray, step: float = 0.1) -> Loop:
    """The closed path along ``inner`` (anticlockwise), a point every ``step`` m, heading along it."""
    closed = np.vstack([inner, inner[:1]])
    seg = np.hypot(*np.diff(closed, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    at = np.arange(int(s[-1] / step)) * step
    xy = np.column_stack([np.interp(at, s, closed[:, 0]), np.interp(at, s, closed[:, 1])])
    ahead = np.roll(xy, -1, axis=0) - xy
    return Loop(xy, np.arctan2(ahead[:, 1], ahead[:, 0]), step)


def _placed(outline: np.ndarray, inner: np.ndarray) -> np.ndarray:
    grid = _grid(outline)
    maps = [RegistrationMap("L0", grid, LikelihoodField(grid))]
    walls = polygon_edges(np.vstack([outline, outline[:1]]))
    return LoopRegistration(walls, maps, "L0", PARAMS, 0.25, LidarModel()).placed_along(_loop(inner))


def test_a_room_that_is_its_own_twin_turned_half_round_places_no_start() -> None:
    outline = np.array([[0.0, 0.0], [12.0, 0.0], [12.0, 4.0], [0.0, 4.0]])
    inner = np.array([[0.7, 0.7], [11.3, 0.7], [11.3, 3.3], [0.7, 3.3]])
    placed = _placed(outline, inner)
    assert placed.shape[1] > 200 and not placed.any()


def test_a_room_with_a_corner_of_its_own_places_the_robot_along_its_loop() -> None:
    outline = np.array([[0.0, 0.0], [12.0, 0.0], [12.0, 4.0], [5.0, 4.0], [5.0, 8.0], [0.0, 8.0]])
    inner = np.array([[0.7, 0.7], [11.3, 0.7], [11.3, 3.3], [4.3, 3.3], [4.3, 7.3], [0.7, 7.3]])
    placed = _placed(outline, inner)
    assert placed[-1].mean() > 0.5  # the whole window
    assert placed[-1].sum() >= placed[0].sum()  # a quarter of it places less


def test_a_start_is_placed_at_the_first_point_its_longest_submap_places() -> None:
    n, step = 400, 0.1  # a 40 m loop
    loop = Loop(np.zeros((n, 2)), np.zeros(n), step)
    placed = np.zeros((3, n), dtype=bool)  # a quarter, a half and the whole 10 m window
    placed[2, 300:320] = True
    entries = [
        Entry(0, 100, np.zeros((0, 3)), 2.0),  # 8 m along the loop make its window, then on to 300
        Entry(0, 310, np.zeros((0, 3)), 0.0),  # at a placed point, but with no window driven yet
        Entry(0, 100, np.zeros((0, 3)), 2.0),  # the same, with a limit short of the placed points
        None,  # never reaches a loop
    ]
    found = lidar_distances(entries[:2] + entries[3:], [placed], [loop], PARAMS, 150.0)
    assert found[0] == pytest.approx(2.0 + 200 * step)
    assert found[1] == pytest.approx(0.0 + (400 - 310 + 300) * step)  # a whole lap on to 300
    assert math.isinf(found[2])
    short = lidar_distances(entries[2:3], [placed], [loop], PARAMS, 15.0)
    assert math.isinf(short[0])
    placed[0, 150:160] = True  # a 2.5 m submap places these: a start driven 2.5-5 m gets them
    early = lidar_distances([Entry(0, 120, np.zeros((0, 3)), 0.0)], [placed], [loop], PARAMS, 150.0)
    assert early[0] == pytest.approx(30 * step)
    late = lidar_distances([Entry(0, 100, np.zeros((0, 3)), 0.0)], [placed], [loop], PARAMS, 150.0)
    assert late[0] == pytest.approx(200 * step)  # 150-160 comes at 5-6 m: the 2.5 m submap no longer


def test_a_loop_shared_out_in_chunks_places_what_it_places_whole() -> None:
    """The survey shares a loop's registrations out on its executor: each is independent, so the
    chunks' outcomes put together are the loop's."""
    outline = np.array([[0.0, 0.0], [12.0, 0.0], [12.0, 4.0], [5.0, 4.0], [5.0, 8.0], [0.0, 8.0]])
    inner = np.array([[0.7, 0.7], [11.3, 0.7], [11.3, 3.3], [4.3, 3.3], [4.3, 7.3], [0.7, 7.3]])
    grid, loop = _grid(outline), _loop(inner)
    maps = [RegistrationMap("L0", grid, LikelihoodField(grid))]
    along = LoopRegistration(
        polygon_edges(np.vstack([outline, outline[:1]])), maps, "L0", PARAMS, 0.25, LidarModel()
    )
    points = along.points(loop)
    right: list[bool] = []
    for lo in range(0, len(points), 7):  # chunks out of order of level and point
        right += along.placed_at(loop, points[lo : lo + 7])
    assert any(right)
    np.testing.assert_array_equal(along.placed_from(loop, points, right), along.placed_along(loop))
