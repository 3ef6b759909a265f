"""The scan fit of the particle filter tells the right side of a wall from the wrong one."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.se2 import Pose2D


def test_scan_fit_tells_the_right_side_of_a_wall_from_the_wrong_one():
    from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
    from initcli.core.filters.particle_filter import LikelihoodField, scan_fit
    from initcli.core.geometry.raycast import ray_segment_distances

    # a 2 m corridor (y 0-2) beside a 10 m room (y 2-12), walls 1 cell thick, 0.05 m cells
    res = 0.05
    cells = np.full((260, 400), FREE, dtype=np.uint8)
    for y in (0.0, 2.0, 12.0):
        row = 259 - int(round(y / res)) - 10
        cells[row, :] = OCCUPIED
    cells[:, 0] = cells[:, 399] = OCCUPIED
    grid = OccupancyGrid(cells, res, (0.0, -0.5, 0.0))
    field = LikelihoodField(grid)
    walls = np.array(
        [[0, 0, 20, 0], [0, 2, 20, 2], [0, 12, 20, 12], [0, 0, 0, 12], [19.95, 0, 19.95, 12]], float
    )
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    truth = Pose2D(10.0, 1.0, 0.0)
    ranges = ray_segment_distances(truth.xy, angles, walls, 20.0)
    assert scan_fit(truth, angles, ranges, 20.0, field) > 0.9
    wrong = Pose2D(10.0, 3.0, 0.0)  # the room side of the same wall
    assert scan_fit(wrong, angles, ranges, 20.0, field) < 0.6


def test_likelihood_field_lookup_reads_cells_and_max_distance_off_the_map() -> None:
    from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
    from initcli.core.filters.particle_filter import LikelihoodField

    cells = np.full((20, 30), FREE, dtype=np.uint8)
    cells[:, 10] = OCCUPIED  # a wall at x 0.5-0.55 (column 10, 5 cm cells, origin 0)
    field = LikelihoodField(OccupancyGrid(cells, 0.05, (0.0, 0.0, 0.0)), max_distance=0.3)
    x = np.array([[0.525, 0.425, 0.025, 1.49, -0.01, 1.51, 0.7]])
    y = np.array([[0.5, 0.5, 0.5, 0.99, 0.5, 0.5, 1.2]])
    d = field.lookup(x, y)
    assert d.shape == x.shape and d.dtype == np.float32
    assert d[0, 0] == 0.0  # on the wall
    assert math.isclose(float(d[0, 1]), 0.10, abs_tol=1e-6)  # two cells from it
    assert d[0, 2] == np.float32(0.3) and d[0, 3] == np.float32(0.3)  # capped at max_distance
    assert all(d[0, 4:] == np.float32(0.3))  # left of, right of and above the map


def test_the_interpolated_field_meets_the_cells_at_their_centres_and_is_smooth_between():
    from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
    from initcli.core.filters.particle_filter import LikelihoodField

    cells = np.full((40, 40), FREE, dtype=np.uint8)
    cells[:, 5] = OCCUPIED  # a wall whose cell centres lie at x = 0.275
    field = LikelihoodField(OccupancyGrid(cells, 0.05, (0.0, 0.0, 0.0)), max_distance=1.0)
    centres = np.array([0.275, 0.475, 0.975, 1.525])
    y = np.full(4, 1.0 + 0.025)
    assert np.allclose(field.interpolated(centres, y), field.lookup(centres, y), atol=1e-6)
    x = np.linspace(0.3, 1.2, 91)
    d = field.interpolated(x, np.full(91, 1.0))
    assert np.allclose(d, x - 0.275, atol=1e-5)  # linear away from the wall, not in steps
    assert field.interpolated(np.array([-5.0]), np.array([-5.0]))[0] == np.float32(1.0)  # off the map
