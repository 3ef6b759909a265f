"""Frontier exploration on a local grid from the lidar (initcli.core.navigation.frontier)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.records import FREE, OCCUPIED
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.frontier import L_CLAMP, L_FREE, L_OCC, OCC_ABOVE, FrontierParams, LocalMap

# A 10 x 10 m room (x, y in [0, 10]) with a 1.2 m doorway in its east wall at y in [4.4, 5.6],
# and a corridor beyond it.
ROOM = np.array(
    [
        [0.0, 0.0, 10.0, 0.0],
        [10.0, 0.0, 10.0, 4.4],
        [10.0, 5.6, 10.0, 10.0],
        [10.0, 10.0, 0.0, 10.0],
        [0.0, 10.0, 0.0, 0.0],
        [10.0, 3.0, 30.0, 3.0],  # the corridor's walls
        [10.0, 7.0, 30.0, 7.0],
    ]
)
ANGLES = np.linspace(-math.pi, math.pi, 360, endpoint=False)


def scan_at(pose: Pose2D, max_range: float = 20.0) -> np.ndarray:
    return ray_segment_distances(np.array([pose.x, pose.y]), pose.yaw + ANGLES, ROOM, max_range)


def test_integrate_marks_free_space_and_walls() -> None:
    local = LocalMap(FrontierParams(half_size=40.0))
    pose = Pose2D(5.0, 5.0, 0.0)
    local.integrate(pose, ANGLES, scan_at(pose), 20.0)
    grid, _ = local.occupancy()
    assert grid.value_at(5.0, 5.0) == FREE
    assert grid.value_at(2.0, 8.0) == FREE
    assert grid.value_at(5.0, 10.02) == OCCUPIED
    assert OCCUPIED in (grid.value_at(-0.1, 3.0), grid.value_at(0.1, 3.0))


def test_the_best_frontier_leads_out_of_the_room() -> None:
    local = LocalMap(FrontierParams(half_size=40.0))
    pose = Pose2D(5.0, 5.0, 0.0)
    for yaw in (0.0, 2.0, 4.0):
        p = Pose2D(5.0, 5.0, yaw)
        local.integrate(p, ANGLES, scan_at(p), 20.0)
    frontiers = local.frontiers()
    assert frontiers, "the doorway opens onto unknown space"
    # Beams reach 8 m into the corridor through the doorway; the frontier lies beyond the doorway.
    assert all(f.centre[0] > 10.0 for f in frontiers)
    route = local.plan(pose)
    assert route and route[-1][0] > 10.0
    # Each waypoint lies in space the lidar has seen free (the route goes through the doorway).
    grid, _ = local.occupancy()
    assert all(grid.value_at(float(w[0]), float(w[1])) == FREE for w in route)
    assert any(4.4 < w[1] < 5.6 and 9.0 < w[0] < 11.5 for w in route)


def test_a_failed_target_is_not_chosen_again_and_a_closed_room_has_none() -> None:
    closed = ROOM.copy()
    closed[1] = [10.0, 0.0, 10.0, 10.0]  # no doorway
    local = LocalMap(FrontierParams(half_size=40.0))
    pose = Pose2D(5.0, 5.0, 0.0)
    ranges = ray_segment_distances(np.array([5.0, 5.0]), ANGLES, closed, 20.0)
    local.integrate(pose, ANGLES, ranges, 20.0)
    assert local.plan(pose) == []
    open_map = LocalMap(FrontierParams(half_size=40.0))
    open_map.integrate(pose, ANGLES, scan_at(pose), 20.0)
    route = open_map.plan(pose)
    assert route
    open_map.give_up(route[-1])
    again = open_map.plan(pose)
    if again:  # it leads to a frontier 1.5 m or more from the failed target (the route ends at the
        # planner's cell nearest that frontier), not to one within 1.5 m of it

        def gap(a: np.ndarray, b: np.ndarray) -> float:
            return float(np.hypot(*(a - b)))

        fronts = open_map.frontiers()
        far = [f.centre for f in fronts if gap(f.centre, route[-1]) >= 1.5]
        near = [f.centre for f in fronts if gap(f.centre, route[-1]) < 1.5]
        assert far and min(gap(again[-1], c) for c in far) < min(
            (gap(again[-1], c) for c in near), default=9.0
        )
    # forgotten, the doorway is a way out again (a lap that finds no other: not shut in)
    assert open_map.forget_failures() and not open_map.forget_failures()
    assert float(np.hypot(*(open_map.plan(pose)[-1] - route[-1]))) < 1.5


def room_seen(way: tuple[float, float]) -> LocalMap:
    """A local map of a closed 6 x 4 m room seen free inside its walls, and through its east wall a
    strip at y 2 of ``way`` (m long, m wide) cleared into the unknown beyond."""
    local = LocalMap(FrontierParams(half_size=20.0))

    def fill(x0: float, x1: float, y0: float, y1: float, value: float) -> None:
        xs, ys = np.meshgrid(np.arange(x0, x1 + 1e-9, 0.1), np.arange(y0, y1 + 1e-9, 0.1))
        r, c = local.cells_of(np.column_stack([xs.ravel(), ys.ravel()]))
        local.logodds[r, c] = value

    fill(-0.2, 6.2, -0.2, 4.2, L_CLAMP)  # the walls ...
    fill(0.1, 5.9, 0.1, 3.9, -L_CLAMP)  # ... round the room
    length, width = way
    fill(5.9, 6.0 + length, 2.0 - width / 2, 2.0 + width / 2, -L_CLAMP)
    return local


@pytest.mark.parametrize("length", [1.4, 2.0, 3.0])
def test_a_beam_through_a_closed_room_s_wall_is_no_way_out(length: float) -> None:
    """A beam through a glass pane, or past a leaf's edge, clears one line of cells through the wall
    into the unknown: no frontier, no route for a lap (the room is shut in). The old map took the
    line for an opening and sent the robot to the wall in front of it, lap after lap."""
    local = room_seen((length, 0.1))
    assert local.frontiers() == []
    assert local.plan(Pose2D(3.0, 2.0, 0.0), 0.25, spacing=0.5, prefer=0.45) == []


def test_a_doorway_through_the_same_wall_is_a_way_out() -> None:
    local = room_seen((3.0, 0.8))
    assert local.frontiers()
    route = local.plan(Pose2D(3.0, 2.0, 0.0), 0.25, spacing=0.5, prefer=0.45)
    assert route and route[-1][0] > 6.2


def numpy_integrate(
    local: LocalMap, pose: Pose2D, angles: np.ndarray, ranges: np.ndarray, range_max: float
) -> None:
    """The vectorised form the compiled update replaced: unique cells per scan, end points first."""
    p = local.params
    ok = np.isfinite(ranges) & (ranges > 0.05)
    a, r = pose.yaw + angles[ok], ranges[ok]
    hit = r < min(range_max, p.integrate_range)
    reach = np.minimum(r, p.integrate_range)
    lost = r >= range_max
    t = np.arange(0.0, p.integrate_range, p.resolution * 0.7)[None, :]
    along = t < reach[:, None]
    n = local.logodds.shape[0]
    flat = local.logodds.reshape(-1)

    def cells(xy: np.ndarray) -> np.ndarray:
        rr, cc = local.cells_of(xy)
        inside = (rr >= 0) & (rr < n) & (cc >= 0) & (cc < n)
        return np.unique(rr[inside] * n + cc[inside])

    ends = cells(np.column_stack([pose.x + r[hit] * np.cos(a[hit]), pose.y + r[hit] * np.sin(a[hit])]))
    flat[ends] = np.minimum(flat[ends] + L_OCC, L_CLAMP)
    # a beam with no return stops at the first cell occupied after the end points were written
    xs, ys = pose.x + t * np.cos(a)[:, None], pose.y + t * np.sin(a)[:, None]
    rr, cc = local.cells_of(np.column_stack([xs.ravel(), ys.ravel()]))
    rr, cc = rr.reshape(xs.shape), cc.reshape(xs.shape)
    inside = (rr >= 0) & (rr < n) & (cc >= 0) & (cc < n)
    blocked = inside & (flat[np.where(inside, rr * n + cc, 0)] > OCC_ABOVE) & lost[:, None]
    along &= np.cumsum(blocked, axis=1) == 0
    free_xy = np.column_stack([xs[along], ys[along]])
    free = np.setdiff1d(cells(free_xy), ends, assume_unique=True)
    flat[free] = np.maximum(flat[free] + L_FREE, -L_CLAMP)


def test_integrate_equals_the_vectorised_update_bit_for_bit() -> None:
    """Scans from many poses, some beyond the grid's edge, some beams missing or out of range:
    the compiled per-cell update leaves exactly the log-odds of the numpy form."""
    rng = np.random.default_rng(3)
    params = FrontierParams(half_size=12.0, integrate_range=8.0)
    compiled, reference = LocalMap(params), LocalMap(params)
    for _ in range(60):
        pose = Pose2D(float(rng.uniform(-2, 32)), float(rng.uniform(-4, 14)), float(rng.uniform(-4, 4)))
        ranges = scan_at(pose)
        ranges[rng.random(len(ranges)) < 0.05] = np.inf
        ranges[rng.random(len(ranges)) < 0.02] = 0.01
        compiled.integrate(pose, ANGLES, ranges, 20.0)
        numpy_integrate(reference, pose, ANGLES, ranges, 20.0)
    np.testing.assert_array_equal(compiled.logodds, reference.logodds)
    assert (compiled.logodds > 0).any() and (compiled.logodds < 0).any()


def test_a_route_that_prefers_clearance_passes_the_doorway_through_its_middle() -> None:
    """From a corner of the room the shortest path cuts the doorway's jamb; preferring clearance,
    the route crosses the doorway near its middle (y 5.0), on cells the lidar saw free."""
    local = LocalMap(FrontierParams(half_size=40.0))
    for x, y in ((5.0, 5.0), (8.0, 1.5), (8.5, 8.5)):
        for yaw in (0.0, 2.0, 4.0):
            p = Pose2D(x, y, yaw)
            local.integrate(p, ANGLES, scan_at(p), 20.0)
    pose = Pose2D(8.5, 8.5, 0.0)
    plain = local.plan(pose, 0.25, spacing=0.5)
    centred = local.plan(pose, 0.25, spacing=0.5, prefer=0.45)
    assert plain and centred

    def crossing(route: list[np.ndarray]) -> float:
        """y where the route's segments cross the wall line x = 10."""
        for a, b in zip(route[:-1], route[1:], strict=True):
            if a[0] < 10.0 <= b[0]:
                return float(a[1] + (b[1] - a[1]) * (10.0 - a[0]) / (b[0] - a[0]))
        raise AssertionError("the route does not leave the room")

    assert abs(crossing(centred) - 5.0) <= 0.25  # a cell (0.2 m) off the middle at most
    assert abs(crossing(plain) - 5.0) > abs(crossing(centred) - 5.0)
    grid, _ = local.occupancy()
    assert all(grid.value_at(float(w[0]), float(w[1])) == FREE for w in centred)
