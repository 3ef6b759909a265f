"""initcli.sim.synthetic_paths: random collision-free paths through a small occupancy grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.records import OccupancyGrid
from initcli.sim.synthetic_paths import random_path

RES = 0.1  # m per cell


def _hall(width_m: float = 30.0, height_m: float = 4.0) -> OccupancyGrid:
    """A walled 30 m x 4 m hall: 255 free inside, 0 occupied on a 2-cell border; origin (0, 0)."""
    rows, cols = int(round(height_m / RES)), int(round(width_m / RES))
    cells = np.full((rows, cols), 255, dtype=np.uint8)
    cells[:2, :] = cells[-2:, :] = 0
    cells[:, :2] = cells[:, -2:] = 0
    return OccupancyGrid(cells, RES, (0.0, 0.0, 0.0))


def _length(points: list[tuple[float, float]]) -> float:
    p = np.asarray(points)
    return float(np.sum(np.hypot(*np.diff(p, axis=0).T)))


def test_path_lies_inside_with_clearance_and_has_the_requested_length() -> None:
    grid = _hall()
    for seed in range(3):
        path = random_path(grid, np.random.default_rng(seed), min_length=8.0, max_length=20.0, clearance=0.6)
        assert len(path) >= 2
        xs, ys = np.array(path).T
        assert np.all((xs >= 0.2 + 0.6 - 0.25) & (xs <= 29.8 - 0.6 + 0.25))
        assert np.all((ys >= 0.2 + 0.6 - 0.25) & (ys <= 3.8 - 0.6 + 0.25))
        # simplification only drops points, so the polyline is no longer than the grid path
        assert 8.0 * 0.9 <= _length(path) <= 20.0 + 1e-9


def test_same_seed_same_path() -> None:
    grid = _hall()
    a = random_path(grid, np.random.default_rng(5), min_length=5.0, max_length=15.0)
    b = random_path(grid, np.random.default_rng(5), min_length=5.0, max_length=15.0)
    assert a == b


def test_straight_corridor_path_simplifies_to_few_waypoints() -> None:
    grid = _hall(height_m=2.0)  # only the two middle 0.25 m cells keep 0.6 m clearance
    for seed in range(3):
        path = random_path(grid, np.random.default_rng(seed), min_length=5.0, max_length=20.0, clearance=0.6)
        assert len(path) == 2
        assert all(0.85 <= y <= 1.15 for _, y in path)


def test_start_near_a_given_point() -> None:
    grid = _hall()
    near = np.array([[25.0, 2.0]])
    path = random_path(grid, np.random.default_rng(2), min_length=5.0, max_length=15.0, near=near)
    assert math.hypot(path[0][0] - 25.0, path[0][1] - 2.0) < 0.5


def test_no_clearance_or_no_long_enough_path_raises() -> None:
    grid = _hall()
    with pytest.raises(ValueError, match="clearance"):
        random_path(grid, np.random.default_rng(0), clearance=3.0)
    with pytest.raises(ValueError, match="length"):
        random_path(grid, np.random.default_rng(0), min_length=60.0, max_length=80.0, tries=3)
