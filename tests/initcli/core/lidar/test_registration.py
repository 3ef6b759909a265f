"""The lidar submap registration over the BIM map: finds the pose where the walls single it out,
refuses where they repeat."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from bimtools.site.records import OccupancyGrid
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.registration import (
    GRID,
    RegistrationMap,
    open_doorways,
    register,
    shut_doorways,
    thin_points,
    wall_crossings,
)
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.scan_fit import BeamEnds, ScanSample
from tests.helpers import walls_grid

RES = 0.05
# An asymmetric floor: a 30 x 12 m hall, a wall across it with a doorway, a room in one corner and
# a column (a 1 m square) in the other part.
FLOOR = np.array(
    [
        [0, 0, 30, 0],
        [30, 0, 30, 12],
        [30, 12, 0, 12],
        [0, 12, 0, 0],
        [12, 0, 12, 5],
        [12, 7, 12, 12],
        [0, 8, 5, 8],
        [5, 8, 5, 10],
        [22, 4, 23, 4],
        [23, 4, 23, 5],
        [23, 5, 22, 5],
        [22, 5, 22, 4],
    ],
    dtype=float,
)
# A plain corridor 60 m long and 2.4 m wide: every place along its middle looks alike.
CORRIDOR = np.array([[0, 0, 60, 0], [60, 0, 60, 2.4], [60, 2.4, 0, 2.4], [0, 2.4, 0, 0]], dtype=float)


def grid_of(walls: np.ndarray) -> OccupancyGrid:
    """The walls drawn one cell thick, free inside their bounding box, 1 m of margin."""
    return walls_grid(walls, RES)


def drive(walls: np.ndarray, path: list[Pose2D], odom_start: Pose2D) -> list[ScanSample]:
    """Scans cast in the true world at each pose of ``path``, with odometry starting at ``odom_start``
    (an odometry frame unrelated to the map's)."""
    angles = np.linspace(-math.pi, math.pi, 180, endpoint=False)
    to_odom = odom_start * path[0].inverse()
    scans = []
    for pose in path:
        ranges = ray_segment_distances(np.array([pose.x, pose.y]), angles + pose.yaw, walls, 15.0)
        ranges = np.where(ranges < 15.0, ranges, np.inf)
        scans.append(ScanSample(to_odom * pose, angles, ranges, 15.0))
    return scans


def line(x0: float, y0: float, x1: float, y1: float, step: float = 0.5) -> list[Pose2D]:
    n = int(math.hypot(x1 - x0, y1 - y0) / step) + 1
    yaw = math.atan2(y1 - y0, x1 - x0)
    return [
        Pose2D(float(x), float(y), yaw)
        for x, y in zip(np.linspace(x0, x1, n), np.linspace(y0, y1, n), strict=True)
    ]


def registered(walls: np.ndarray, path: list[Pose2D]) -> tuple[object, Pose2D]:
    grid = grid_of(walls)
    scans = drive(walls, path, Pose2D(3.0, -7.0, 1.0))
    found = register(
        BeamEnds.of(scans), [RegistrationMap("L1", grid, LikelihoodField(grid))], RegistrationParams(), 0.25
    )
    return found, path[-1]


def test_the_submap_of_an_asymmetric_floor_registers_at_the_true_pose() -> None:
    path = line(8.0, 2.5, 8.0, 6.0) + line(8.0, 6.0, 18.0, 6.0)  # up, then east through the doorway
    found, truth = registered(FLOOR, path)
    assert found.unique, found.why
    best = found.best
    assert best is not None and best.storey == "L1"
    assert best.pose.distance_to(truth) < 0.2
    assert math.degrees(best.pose.yaw_error(truth)) < 2.0
    assert best.fit > 0.95


def test_a_plain_corridor_is_refused_where_every_place_looks_alike() -> None:
    found, truth = registered(CORRIDOR, line(20.0, 1.2, 35.0, 1.2))
    assert not found.unique
    assert found.best is not None and found.rival is not None
    assert found.best.fit > 0.9 and found.rival.fit > found.best.fit - 0.15  # both fit: no pose
    assert found.contested and "fit within" in found.why


def test_a_submap_too_thin_to_judge_is_refused() -> None:
    grid = grid_of(FLOOR)
    ends = BeamEnds(Pose2D.identity(), np.array([[1.0, 0.0], [0.0, 1.0]]), np.array([2.0]))
    found = register(ends, [RegistrationMap("L1", grid, LikelihoodField(grid))], RegistrationParams(), 0.25)
    assert not found.unique and found.best is None


def test_thinning_keeps_one_point_per_cell_and_at_most_the_limit() -> None:
    xy = np.array([[0.01, 0.01], [0.02, 0.02], [0.5, 0.5], [1.0, 1.0], [1.01, 1.02]])
    assert len(thin_points(xy, 0.1, 100)) == 3
    assert len(thin_points(np.random.default_rng(0).uniform(0, 50, (5000, 2)), 0.1, 300)) == 300


# A 30 x 2.4 m corridor turned half round is itself, and so are its two rooms (north at x 5-10,
# south at x 20-25); their doorways are not (north at x 6-7, south at x 21-22, not 23-24).
HALF_TURN = np.array(
    [
        [0, 0, 0, 2.4],
        [30, 0, 30, 2.4],
        [0, 2.4, 6, 2.4],
        [7, 2.4, 30, 2.4],
        [0, 0, 21, 0],
        [22, 0, 30, 0],
        [5, 2.4, 5, 7.4],
        [5, 7.4, 10, 7.4],
        [10, 7.4, 10, 2.4],
        [20, 0, 20, -5],
        [20, -5, 25, -5],
        [25, -5, 25, 0],
    ],
    dtype=float,
)


def test_beams_through_walls_rule_out_the_place_turned_half_round() -> None:
    """The walls alone fit the corridor and its half turn alike; the beams through the doorways
    cross walls only at the half turn, so the registration is unique there, at the true pose."""
    grid = grid_of(HALF_TURN)
    maps = [RegistrationMap("L1", grid, LikelihoodField(grid))]
    path = line(2.0, 1.2, 28.0, 1.2)
    ends = BeamEnds.of(drive(HALF_TURN, path, Pose2D(3.0, -7.0, 1.0)))
    walls_only = register(ends, maps, RegistrationParams(see_through=0.0), 0.25)
    assert not walls_only.unique and walls_only.contested, walls_only.why
    twin = walls_only.contested[0]
    assert twin.pose.distance_to(Pose2D(30.0 - path[-1].x, 2.4 - path[-1].y, 0.0)) < 0.5
    found = register(ends, maps, RegistrationParams(), 0.25)
    assert found.unique, found.why
    assert found.best is not None and found.best.pose.distance_to(path[-1]) < 0.3  # the coarse pose
    assert found.through[1] >= found.through[0] + RegistrationParams().see_through
    assert "through their walls" in found.why


def test_a_submap_of_few_beams_rules_out_nothing_by_beams_through_walls() -> None:
    """One scan in HALF_TURN's corridor: its places alike differ by three beams through a doorway
    (of 176, a share above ``see_through``), as few as a door the model lacks sends through on site;
    under ``through_min_sampled`` beams the scan stays undecided."""
    grid = grid_of(HALF_TURN)
    maps = [RegistrationMap("L1", grid, LikelihoodField(grid))]
    ends = BeamEnds.of(drive(HALF_TURN, [Pose2D(24.0, 1.8, 0.3)], Pose2D(3.0, -7.0, 1.0)))
    assert len(ends.xy) < GRID.through_min_sampled
    any_size = register(ends, maps, RegistrationParams(), 0.25, replace(GRID, through_min_sampled=0))
    assert any_size.unique and "through their walls" in any_size.why  # decided by three beams
    assert round((min(any_size.through[1:]) - any_size.through[0]) * len(ends.xy)) == 3
    found = register(ends, maps, RegistrationParams(), 0.25)
    assert not found.unique and "fit within" in found.why, found.why
    assert found.through == ()


# HALF_TURN as its model draws it: the doors closed, so the map's walls run on across them.
HALF_TURN_DOORS_CLOSED = np.array(
    [[0, 0, 0, 2.4], [30, 0, 30, 2.4], [0, 2.4, 30, 2.4], [0, 0, 30, 0], *HALF_TURN[6:].tolist()], dtype=float
)
# Its two doors: face centre, normal into the corridor, width (the doorways of HALF_TURN).
HALF_TURN_DOORS = np.array([[6.5, 2.4, 0.0, -1.0, 1.0], [21.5, 0.0, 0.0, 1.0, 1.0]])


def test_open_doorways_frees_each_door_through_its_wall_and_nothing_else() -> None:
    grid = grid_of(HALF_TURN_DOORS_CLOSED)
    opened = open_doorways(grid, HALF_TURN_DOORS, slack=0.3, depth=0.6, front=0.2)

    def wall(g: OccupancyGrid, x: float, y: float) -> bool:
        return bool(g.cells[g.world_to_cell(x, y)] == 0)

    for x in (6.5, 5.8, 7.2):  # the door's middle and its widened edges
        assert wall(grid, x, 2.4) and not wall(opened, x, 2.4)
    assert not wall(opened, 21.5, 0.0) and wall(opened, 23.5, 0.0)  # the other door, not its half turn
    for x in (5.6, 7.4, 15.0):  # beyond the widened door: still wall
        assert wall(opened, x, 2.4)
    assert wall(opened, 5.0, 4.0) and wall(opened, 7.0, 7.4)  # the room behind keeps its walls
    assert open_doorways(grid, np.zeros((0, 5)), 0.3, 0.6, 0.2).cells.tobytes() == grid.cells.tobytes()


def test_open_doorways_cuts_through_a_thick_wall_from_the_side_its_normal_faces() -> None:
    """A wall 0.3 m thick between y 2.0 and 2.3 (its faces drawn), a door on its lower face facing
    down (-y): the opening runs through the wall behind the face, and a door facing the other way
    from the same point would leave the wall behind it closed."""
    grid = walls_grid(np.array([[0, 2.0, 10, 2.0], [0, 2.3, 10, 2.3], [0, 0, 0, 5], [10, 0, 10, 5]]), RES)
    door = np.array([[5.0, 2.0, 0.0, -1.0, 1.0]])
    opened = open_doorways(grid, door, slack=0.3, depth=0.6, front=0.2)

    def occupied(g: OccupancyGrid, x: float, y: float) -> bool:
        return bool(g.cells[g.world_to_cell(x, y)] == 0)

    assert occupied(grid, 5.0, 2.0) and occupied(grid, 5.0, 2.3)
    assert not occupied(opened, 5.0, 2.0) and not occupied(opened, 5.0, 2.3)  # both faces, 0.3 m behind
    assert not occupied(opened, 5.7, 2.3) and occupied(opened, 5.9, 2.3)  # widened by the slack only
    backwards = open_doorways(grid, door * [1, 1, 0, -1, 1], slack=0.3, depth=0.6, front=0.2)
    assert not occupied(backwards, 5.0, 2.0) and occupied(backwards, 5.0, 2.3)  # only 0.2 m in front


def thick_wall(doorways: list[tuple[float, float]], leaves: bool = False) -> np.ndarray:
    """A corridor 20 m long below a wall 0.3 m thick (faces at y 2.4 and 2.7), the wall broken by
    ``doorways`` (x from, x to) with their jambs drawn, rooms' back wall at y 6; ``leaves``: a shut
    leaf across each doorway in the middle of the wall (y 2.55), where a frame holds it."""
    walls = [[0, 0, 20, 0], [0, 0, 0, 6], [20, 0, 20, 6], [0, 6, 20, 6]]
    x = 0.0
    for a, b in doorways:
        walls += [[x, 2.4, a, 2.4], [x, 2.7, a, 2.7], [a, 2.4, a, 2.7], [b, 2.4, b, 2.7]]
        if leaves:
            walls.append([a, 2.55, b, 2.55])
        x = b
    walls += [[x, 2.4, 20, 2.4], [x, 2.7, 20, 2.7]]
    return np.array(walls, dtype=float)


def occupied_at(g: OccupancyGrid, x: float, y: float) -> bool:
    return bool(g.cells[g.world_to_cell(x, y)] == 0)


def test_shut_doorways_fills_each_opening_across_its_wall_and_nothing_else() -> None:
    """A door placed in the middle of the wall (as an IFC door is), one whose opening is wider than
    the door (a frame not in the section): each opening filled from face to face, nothing in front
    of it or behind it; a door with no wall round it and a map that shows its doors shut are left."""
    grid = walls_grid(thick_wall([(4.5, 5.5), (7.4, 8.6)]), RES)
    doors = np.array([[5.0, 2.55, 0.0, -1.0, 1.0], [8.0, 2.55, 0.0, -1.0, 1.0], [14.0, 1.2, 0.0, 1.0, 1.0]])
    shut = shut_doorways(grid, doors, GRID.door_slack, GRID.door_depth, GRID.door_front)
    for x in (4.6, 5.0, 5.4, 7.5, 8.0, 8.5):
        for y in (2.42, 2.55, 2.68):  # the doorway, face to face
            assert not occupied_at(grid, x, y) and occupied_at(shut, x, y), (x, y)
        assert not occupied_at(shut, x, 2.2) and not occupied_at(shut, x, 2.9)  # in front, behind
    changed = shut.cells != grid.cells
    assert changed.sum() <= 1.1 * (1.0 + 1.2) * 0.3 / RES**2 + 2 * 2.2 / RES  # the two openings only
    assert not changed[grid.world_to_cell(14.0, 1.2)]  # the door in the open corridor: nothing
    odd = np.array([[5.0, 2.55, 0.0, -1.0, w] for w in (0.0, -1.0, 1e6)])  # a features.csv allows them
    assert shut_doorways(grid, odd, GRID.door_slack, GRID.door_depth, GRID.door_front).cells.tobytes() == (
        grid.cells.tobytes()
    )
    assert shut_doorways(shut, doors, GRID.door_slack, GRID.door_depth, GRID.door_front).cells.tobytes() == (
        shut.cells.tobytes()
    )  # drawn shut already: unchanged


def test_shut_leaves_fit_the_map_with_its_doors_shut() -> None:
    """On site the doors are shut, their leaves set in the middle of the wall; the model's map leaves
    the doorways free. The beams that end on the leaves miss the map as drawn and fit the map with
    its doors shut, at the true pose."""
    doorways = [(2.0, 3.0), (6.5, 7.5), (12.0, 13.0), (16.0, 17.0)]
    grid = walls_grid(thick_wall(doorways), RES)
    doors = np.array([[(a + b) / 2, 2.55, 0.0, -1.0, b - a] for a, b in doorways])
    shut = LikelihoodField(shut_doorways(grid, doors, GRID.door_slack, GRID.door_depth, GRID.door_front))
    path = line(1.0, 1.2, 19.0, 1.2)
    ends = BeamEnds.of(drive(thick_wall(doorways, leaves=True), path, Pose2D(3.0, -7.0, 1.0)))
    drawn = register(ends, [RegistrationMap("L1", grid, LikelihoodField(grid))], RegistrationParams(), 0.1)
    fits = register(
        ends, [RegistrationMap("L1", grid, LikelihoodField(grid), fit=shut)], RegistrationParams(), 0.1
    )
    assert drawn.best is not None and fits.best is not None
    assert fits.best.pose.distance_to(path[-1]) < 0.1, fits.why
    assert fits.best.fit >= 0.98 and drawn.best.fit < fits.best.fit - 0.03, (drawn.why, fits.why)


def test_beams_through_doors_the_map_draws_closed_rule_out_the_half_turn() -> None:
    """On site the doors stand open, in the model's map they are walls: through the map's walls the
    true pose's beams cross them as much as the half turn's, and nothing is ruled out; through the
    map with the model's doors open only the half turn's beams cross walls, and it is ruled out."""
    grid = grid_of(HALF_TURN_DOORS_CLOSED)
    field_ = LikelihoodField(grid)
    opened = LikelihoodField(
        open_doorways(grid, HALF_TURN_DOORS, GRID.door_slack, GRID.door_depth, GRID.door_front)
    )
    path = line(2.0, 1.2, 28.0, 1.2)
    ends = BeamEnds.of(drive(HALF_TURN, path, Pose2D(3.0, -7.0, 1.0)))
    closed = register(ends, [RegistrationMap("L1", grid, field_)], RegistrationParams(), 0.25)
    assert not closed.unique and closed.contested, closed.why
    found = register(ends, [RegistrationMap("L1", grid, field_, through=opened)], RegistrationParams(), 0.25)
    assert found.unique, found.why
    assert found.best is not None and found.best.pose.distance_to(path[-1]) < 0.3
    assert found.through[0] <= GRID.through_best < found.through[1] and found.doors_open


def test_doors_where_the_half_turn_s_beams_cross_leave_the_map_as_drawn_to_rule_it_out() -> None:
    """The model has doors (shut on site) just where the half turn's beams cross its walls: with
    them open every beam is excused, but on the map as drawn the half turn is still ruled out."""
    grid = grid_of(HALF_TURN)
    field_ = LikelihoodField(grid)
    twins = np.array(
        [[23.5, 0.0, 0.0, 1.0, 1.0], [8.5, 2.4, 0.0, -1.0, 1.0]]
    )  # the doorways turned half round
    opened = LikelihoodField(open_doorways(grid, twins, GRID.door_slack, GRID.door_depth, GRID.door_front))
    path = line(2.0, 1.2, 28.0, 1.2)
    ends = BeamEnds.of(drive(HALF_TURN, path, Pose2D(3.0, -7.0, 1.0)))
    only_open = register(ends, [RegistrationMap("L1", grid, opened)], RegistrationParams(), 0.25)
    assert not only_open.unique, only_open.why  # the doors excuse the half turn's beams
    found = register(ends, [RegistrationMap("L1", grid, field_, through=opened)], RegistrationParams(), 0.25)
    assert found.unique, found.why
    assert found.best is not None and found.best.pose.distance_to(path[-1]) < 0.3


def test_wall_crossings_count_beams_that_pass_a_wall_well_before_their_end() -> None:
    grid = grid_of(np.array([[5.0, -5.0, 5.0, 5.0]]))
    origins = np.zeros((3, 2))
    ends = np.array([[4.9, 0.0], [8.0, 0.0], [5.5, 1.0]])  # short of it, through it, just behind it
    field_ = LikelihoodField(grid)
    assert wall_crossings(origins, ends, Pose2D.identity(), field_, 0.75, 0.5) == pytest.approx(1 / 3)
    assert wall_crossings(origins, ends, Pose2D(0.0, 0.0, math.pi), field_, 0.75, 0.5) == 0.0
    along = np.array([[4.0, 0.0], [4.8, 4.0]])  # a beam that grazes the wall 0.2 m into it: not through
    assert wall_crossings(along[:1], along[1:], Pose2D(0.4, 0.0, 0.0), field_, 0.75, 0.5) == 0.0
