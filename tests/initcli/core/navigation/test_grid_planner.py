"""initcli.core.navigation.grid_planner: clearance-aware shortest paths on an occupancy grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
from initcli.core.navigation.grid_planner import PlanningGrid, with_doors_closed


def _u_corridor(resolution: float = 0.1) -> OccupancyGrid:
    """A 10 x 6 m free room with a wall from x=4.5 to 5.5, y=0 to 4.5 (pass above it at y > 4.5).

    Row 0 of ``cells`` is the top (highest y), as in a map_server image.
    """
    rows, cols = int(6 / resolution), int(10 / resolution)
    world = np.full((rows, cols), FREE, dtype=np.uint8)  # row 0 = lowest y here
    world[[0, -1], :] = OCCUPIED
    world[:, [0, -1]] = OCCUPIED
    world[: int(4.5 / resolution), int(4.5 / resolution) : int(5.5 / resolution)] = OCCUPIED
    return OccupancyGrid(cells=np.flipud(world).copy(), resolution=resolution, origin=(0.0, 0.0, 0.0))


@pytest.fixture(scope="module")
def planner() -> PlanningGrid:
    return PlanningGrid.of(_u_corridor(), clearance=0.3, cell=0.2)


def test_free_cells_respect_clearance_with_row_zero_at_lowest_y(planner: PlanningGrid) -> None:
    assert planner.cell == pytest.approx(0.2)
    assert planner.free.shape == (30, 50)
    assert not planner.free[0].any()  # the south wall and its clearance
    assert planner.free[10, 10]  # (2.1, 2.1) m: open floor
    assert not planner.free[10, 25]  # (5.1, 2.1) m: inside the dividing wall
    assert planner.free[26, 25]  # (5.1, 5.3) m: the gap above the wall
    assert len(planner.nodes) == int(planner.free.sum())
    assert (planner.index[planner.free] >= 0).all() and (planner.index[~planner.free] == -1).all()


def test_node_at_and_centre(planner: PlanningGrid) -> None:
    node = planner.node_at(2.05, 2.05)
    np.testing.assert_allclose(planner.centre(node), [2.1, 2.1])
    inside_wall = planner.node_at(5.0, 2.0, search=1)
    assert inside_wall == -1
    near = planner.node_at(5.0, 2.0)  # 4 cells search reaches the free floor beside the wall
    assert near >= 0 and abs(planner.centre(near)[0] - 5.0) <= 4 * 0.2 + 0.1 + 1e-9
    assert planner.node_at(-50.0, -50.0) == -1


def test_shortest_path_goes_around_the_wall(planner: PlanningGrid) -> None:
    dist, pred, start = planner.distances_from(2.0, 2.0)
    goal = planner.node_at(8.0, 2.0)
    straight = 6.0
    around = 2 * math.hypot(3.0, 4.8 - 2.0)  # up to the gap and down again, roughly
    assert dist[goal] > straight + 1.0
    assert dist[goal] == pytest.approx(around, rel=0.2)
    waypoints = planner.path(pred, start, goal, spacing=2.0)
    np.testing.assert_allclose(waypoints[-1], planner.centre(goal))
    assert max(p[1] for p in waypoints) > 4.5  # it passes above the wall
    steps = [np.hypot(*(b - a)) for a, b in zip(waypoints[:-1], waypoints[1:], strict=True)]
    assert all(s <= 2.0 + 0.3 for s in steps)


def test_unreachable_and_outside_starts() -> None:
    grid = _u_corridor()
    grid.cells[:, 45:55] = OCCUPIED  # close the gap: east and west halves are apart
    planner = PlanningGrid.of(grid, clearance=0.3, cell=0.2)
    dist, pred, start = planner.distances_from(2.0, 2.0)
    goal = planner.node_at(8.0, 2.0)
    assert math.isinf(dist[goal])
    assert planner.path(pred, start, goal) == []
    dist, pred, start = planner.distances_from(-20.0, -20.0)
    assert start == -1 and np.isinf(dist).all()
    assert planner.path(pred, start, goal) == []


def test_routes_never_pass_a_door() -> None:
    """The gap above the dividing wall is a 1.5 m doorway: with its door shut no route crosses."""
    grid = _u_corridor()
    door = np.array([[5.0, 5.25, 1.0, 0.0, 1.4]])  # in the gap, facing +x, 1.4 m wide
    closed = with_doors_closed(grid, door)
    assert np.array_equal(grid.cells, _u_corridor().cells)  # the map itself is left alone
    for g, crosses in ((grid, True), (closed, False)):
        p = PlanningGrid.of(g, clearance=0.3, cell=0.2)
        dist, _, _ = p.distances_from(2.0, 2.0)
        assert math.isfinite(dist[p.node_at(8.0, 2.0)]) == crosses
