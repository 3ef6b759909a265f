"""The scan jackknife: small where the whole map pins a pose, wide where one part of the scan ends
on something the map lacks."""

from __future__ import annotations

import math

import numpy as np

from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.geometry.raycast import cast_rays
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.scan_jackknife import JackknifeParams, fit_scan_locally, sector_jackknife
from tests.helpers import walls_grid

ROOM = np.array(
    [
        [0.0, 0.0, 10.0, 0.0],
        [10.0, 0.0, 10.0, 6.0],
        [10.0, 6.0, 0.0, 6.0],
        [0.0, 6.0, 0.0, 0.0],
        [6.0, 3.0, 6.3, 3.0],  # a column
        [6.3, 3.0, 6.3, 3.3],
        [6.3, 3.3, 6.0, 3.3],
        [6.0, 3.3, 6.0, 3.0],
    ]
)
HOARDING = np.array([[0.5, 0.6, 7.5, 0.6]])  # on site, not in the model: 0.6 m in front of the south wall
ANGLES = np.radians(np.arange(360.0)) - math.pi


def _scan(pose: Pose2D, walls: np.ndarray) -> np.ndarray:
    ranges = cast_rays(np.array([pose.x, pose.y]), ANGLES + pose.yaw, walls, 20.0)
    return np.where(ranges >= 20.0, np.inf, ranges)


def _sigmas(jack: np.ndarray) -> np.ndarray:
    return np.sqrt(np.diag(jack))


def test_a_scan_of_the_map_as_drawn_moves_the_pose_little():
    field = LikelihoodField(walls_grid(ROOM))
    truth = Pose2D(3.0, 2.5, 0.2)
    jack = sector_jackknife(truth, ANGLES, _scan(truth, ROOM), 20.0, field)
    xy, yaw = _sigmas(jack)[:2], _sigmas(jack)[2]
    assert np.all(xy < 0.03) and yaw < math.radians(1.0)


def test_a_hoarding_the_model_lacks_widens_it_across_the_hoarding():
    field = LikelihoodField(walls_grid(ROOM))
    truth = Pose2D(3.0, 2.5, 0.0)
    ranges = _scan(truth, np.vstack([ROOM, HOARDING]))
    followed = Pose2D(3.0, 2.1, 0.0)  # a filter pulled towards the hoarding: 0.4 m south
    jack = sector_jackknife(followed, ANGLES, ranges, 20.0, field)
    sx, sy, _ = _sigmas(jack)
    assert sy > 0.1 > sx
    error = np.array([0.0, followed.y - truth.y, 0.0])
    floor = np.diag([0.05**2, 0.05**2, math.radians(0.5) ** 2])
    assert error @ np.linalg.solve(jack + floor, error) < 11.34  # inside the 99 % ellipse (3 dof)


def test_the_local_fit_finds_a_shifted_pose_and_stays_put_along_a_corridor():
    field = LikelihoodField(walls_grid(ROOM))
    truth = Pose2D(3.0, 2.5, 0.1)
    ranges = _scan(truth, ROOM)
    ok = np.isfinite(ranges)
    bx, by = ranges[ok] * np.cos(ANGLES[ok]), ranges[ok] * np.sin(ANGLES[ok])
    fit = fit_scan_locally(Pose2D(3.15, 2.4, 0.13), bx, by, field, JackknifeParams())
    assert abs(fit[0] - 3.0) < 0.05 and abs(fit[1] - 2.5) < 0.05 and abs(fit[2] - 0.1) < math.radians(1)
    # a corridor 100 m long, its walls solid rows of cells whose centres lie at y = 0 and y = 2
    cells = np.full((60, 2000), FREE, dtype=np.uint8)
    cells[[19, 59], :] = OCCUPIED
    field = LikelihoodField(OccupancyGrid(cells, 0.05, (-50.0, -0.025, 0.0)))
    corridor = np.array([[-50.0, 0.0, 50.0, 0.0], [-50.0, 2.0, 50.0, 2.0]])
    here = Pose2D(0.0, 1.0, 0.0)
    ranges = _scan(here, corridor)
    ok = np.isfinite(ranges)
    bx, by = ranges[ok] * np.cos(ANGLES[ok]), ranges[ok] * np.sin(ANGLES[ok])
    fit = fit_scan_locally(Pose2D(0.0, 1.08, 0.0), bx, by, field, JackknifeParams())
    assert np.allclose(fit, [0.0, 1.0, 0.0], atol=0.015)  # back across, not a step along


def test_too_few_beams_give_no_jackknife():
    field = LikelihoodField(walls_grid(ROOM))
    ranges = np.full(360, np.inf)
    ranges[:10] = 2.0
    assert not sector_jackknife(Pose2D(3, 2.5, 0), ANGLES, ranges, 20.0, field).any()
