"""initcli.core.lidar.wall_beams: only the beams on a scan's long straight lines are kept."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.scan_fit import ScanSample
from initcli.core.lidar.wall_beams import wall_beams


def _scan(turn: float = 0.0, beams: int = 720) -> ScanSample:
    """A robot 2 m from a straight wall (y = 2, 20 m long) with a 0.3 m box (a chair) 1 m to its
    right, seen by a 360-degree scanner whose first beam points ``turn`` rad from the x axis."""
    angles = turn + np.arange(beams) * 2 * math.pi / beams
    ranges = np.full(beams, np.inf)
    for i, a in enumerate(angles):
        d = np.array([math.cos(a), math.sin(a)])
        if d[1] > 1e-9:
            t = 2.0 / d[1]
            if abs(t * d[0]) <= 10.0:
                ranges[i] = t
        # the box: x in [-0.15, 0.15], y in [-1.3, -1.0]; its near face y = -1.0
        if d[1] < -1e-9:
            t = -1.0 / d[1]
            if abs(t * d[0]) <= 0.15:
                ranges[i] = min(ranges[i], t)
    return ScanSample(Pose2D(0.0, 0.0, 0.0), angles, ranges, 20.0)


def test_the_wall_is_kept_and_the_box_dropped() -> None:
    scan = _scan()
    kept = wall_beams(scan, 1.0)
    on_wall = np.isfinite(scan.ranges) & (np.sin(scan.angles) > 0)
    on_box = np.isfinite(scan.ranges) & (np.sin(scan.angles) < 0)
    assert on_box.sum() > 5 and on_wall.sum() > 100
    assert np.isfinite(kept.ranges[on_wall]).mean() > 0.9  # the wall's beams (ends may be cut)
    assert not np.isfinite(kept.ranges[on_box]).any()  # a 0.3 m face is no wall
    assert kept.odom == scan.odom and kept.range_max == scan.range_max


def test_zero_keeps_every_beam() -> None:
    scan = _scan()
    assert wall_beams(scan, 0.0) is scan


def test_a_wall_across_the_start_of_a_full_turn_keeps_its_beams() -> None:
    scan = _scan(turn=math.pi / 2)  # the first beam points at the wall's middle: it wraps round
    kept = wall_beams(scan, 1.0)
    on_wall = np.isfinite(scan.ranges) & (np.sin(scan.angles) > 0)
    assert np.isfinite(kept.ranges[on_wall]).mean() > 0.9
    assert np.isfinite(kept.ranges[:5]).all() and np.isfinite(kept.ranges[-5:]).all()


def test_clutter_the_map_lacks_no_longer_holds_back_the_registration() -> None:
    """A floor cluttered with furniture its map lacks (0.4 m boxes along every wall): the submap of
    every beam fits the map's walls too poorly to claim; its wall beams alone place the robot."""
    from initcli.core.filters.particle_filter import LikelihoodField
    from initcli.core.lidar.registration import RegistrationMap, register
    from initcli.core.lidar.registration_params import RegistrationParams
    from initcli.core.lidar.scan_fit import BeamEnds
    from tests.initcli.core.lidar.test_registration import FLOOR, drive, grid_of, line

    boxes = []
    rng = np.random.default_rng(3)
    for x in np.arange(1.0, 29.0, 1.3):  # along the long walls, inside
        for y in (0.35, 11.25):
            if 11.0 < x < 13.5:
                continue  # the doorway's wall
            x0, y0 = x + rng.uniform(-0.2, 0.2), y + rng.uniform(-0.15, 0.15)  # not in one line
            boxes += [[x0, y0, x0 + 0.4, y0], [x0 + 0.4, y0, x0 + 0.4, y0 + 0.4]]
            boxes += [[x0 + 0.4, y0 + 0.4, x0, y0 + 0.4], [x0, y0 + 0.4, x0, y0]]
    world = np.vstack([FLOOR, np.array(boxes)])
    grid = grid_of(FLOOR)
    maps = [RegistrationMap("floor", grid, LikelihoodField(grid))]
    path = line(3.0, 3.0, 10.0, 3.0) + line(14.0, 6.0, 20.0, 6.0)[1:]
    scans = drive(world, path, Pose2D(0.0, 0.0, 0.0))
    # a min_fit the cluttered submap misses (its every beam fits 0.75 here, as much clutter as a
    # real office puts under a lower min_fit) and its wall beams reach
    params = RegistrationParams(min_fit=0.78)
    every = register(BeamEnds.of(scans), maps, params, 0.25)
    walls = register(BeamEnds.of([wall_beams(s, 1.0) for s in scans]), maps, params, 0.25)
    assert not every.unique and every.best is not None and every.best.fit < params.min_fit
    assert walls.unique and walls.best is not None
    assert walls.best.pose.distance_to(path[-1]) < 0.3
