"""The bucket grid (initcli.core.geometry.nearest) against scipy's cKDTree: the same nearest points and
the same pairs within a radius, on random sets, duplicates, lines, empty and one-point sets, points
far outside and every path (a whole scan, the buckets, chunks of candidates)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import initcli.core.geometry.nearest as nearest_mod
from initcli.core.geometry.nearest import PointGrid

spatial = pytest.importorskip("scipy.spatial")

BOUNDS = (math.inf, 0.05, 0.1 + 1e-9, 1.0, 7.0)
RADII = (0.0, 0.03, 0.1, 0.7, 2.5, 40.0)


def point_sets(rng: np.random.Generator) -> list[np.ndarray]:
    """Uniform, a lattice with duplicates (ties), a line, clustered with far outliers; small to large."""
    out = [np.zeros((0, 2)), np.array([[1.0, 2.0]]), np.array([[0.0, 0.0], [0.0, 0.0], [3.0, 4.0]])]
    for n in (5, 40, 700, 2000):
        out.append(rng.uniform(-10.0, 10.0, (n, 2)))
        out.append(np.round(rng.uniform(0.0, 5.0, (n, 2)) / 0.05) * 0.05)
        out.append(np.column_stack([rng.uniform(0.0, 50.0, n), np.full(n, 3.0)]))
        out.append(np.vstack([rng.normal(0.0, 1.0, (n - 3, 2)), rng.uniform(-1e3, 1e3, (3, 2))]))
    return out


def queries(rng: np.random.Generator, pts: np.ndarray) -> np.ndarray:
    """Random points, points next to and on the set's, and two far outside it."""
    near = pts[:60] + rng.normal(0.0, 0.01, (min(60, len(pts)), 2))
    return np.vstack([rng.uniform(-15.0, 15.0, (300, 2)), near, pts[:20], [[1e6, -1e6], [0.0, 5e3]]])


def reference_nearest(pts: np.ndarray, q: np.ndarray, bound: float) -> tuple[np.ndarray, np.ndarray]:
    if not len(pts):
        return np.full(len(q), np.inf), np.zeros(len(q), dtype=np.intp)
    dist, index = spatial.cKDTree(pts).query(q, k=1, distance_upper_bound=bound)
    return np.asarray(dist), np.asarray(index)


def reference_within(pts: np.ndarray, q: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    if not len(pts):
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    found = spatial.cKDTree(pts).query_ball_point(q, radius, return_sorted=True)
    lengths = [len(f) for f in found]
    rows = np.repeat(np.arange(len(q)), lengths)
    return rows, np.fromiter(itertools.chain.from_iterable(found), dtype=np.intp, count=sum(lengths))


def check_nearest(grid: PointGrid, pts: np.ndarray, q: np.ndarray, bound: float) -> None:
    dist, index = grid.nearest(q, bound)
    ref_dist, ref_index = reference_nearest(pts, q, bound)
    hit = np.isfinite(ref_dist)
    assert np.array_equal(np.isfinite(dist), hit)
    np.testing.assert_allclose(dist[hit], ref_dist[hit], rtol=1e-12, atol=1e-12)
    assert np.all(index[~hit] == len(pts))
    # the same point, or one as near (a tie)
    other = index[hit] != ref_index[hit]
    mine = np.hypot(*(pts[index[hit]] - q[hit]).T)
    np.testing.assert_allclose(mine[other], ref_dist[hit][other], rtol=1e-12, atol=1e-12)


def check_within(grid: PointGrid, pts: np.ndarray, q: np.ndarray, radius: float) -> None:
    rows, index = grid.within(q, radius)
    ref_rows, ref_index = reference_within(pts, q, radius)
    assert rows.dtype == np.intp and index.dtype == np.intp
    assert np.array_equal(rows, ref_rows)
    assert np.array_equal(index, ref_index)


@pytest.mark.parametrize("cell", [None, 0.1, 0.5, 3.0, 1e-4])
def test_nearest_and_within_match_a_kd_tree(cell: float | None) -> None:
    rng = np.random.default_rng(1)
    for pts in point_sets(rng):
        grid = PointGrid(pts, cell)
        q = queries(rng, pts)
        for bound in BOUNDS:
            check_nearest(grid, pts, q, bound)
        for radius in RADII:
            check_within(grid, pts, q, radius)


def test_small_chunks_and_a_capped_grid_give_the_same_answers(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(nearest_mod, "CANDIDATES", 37)
    monkeypatch.setattr(nearest_mod, "MAX_BUCKETS", 500)
    rng = np.random.default_rng(2)
    for pts in point_sets(rng)[:12]:
        grid = PointGrid(pts, 1e-3)
        assert grid.shape[0] * grid.shape[1] <= 500
        q = queries(rng, pts)
        for bound in (math.inf, 0.1 + 1e-9, 2.0):
            check_nearest(grid, pts, q, bound)
        for radius in (0.0, 0.1, 2.5):
            check_within(grid, pts, q, radius)


def test_the_bucket_path_and_the_scan_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(3)
    pts = np.round(rng.uniform(0.0, 3.0, (400, 2)) / 0.05) * 0.05
    q = queries(rng, pts)
    grid = PointGrid(pts, 0.2)
    buckets = grid.nearest(q, 0.3), grid.within(q, 0.3)
    monkeypatch.setattr(nearest_mod, "SMALL", 10_000)
    scan = grid.nearest(q, 0.3), grid.within(q, 0.3)
    np.testing.assert_array_equal(buckets[0][0], scan[0][0])
    for mine, other in zip(buckets[1], scan[1], strict=True):
        np.testing.assert_array_equal(mine, other)


def test_empty_sets_and_empty_queries() -> None:
    empty = PointGrid(np.zeros((0, 2)))
    dist, index = empty.nearest(np.array([[0.0, 0.0], [1.0, 1.0]]))
    assert np.all(np.isinf(dist)) and np.all(index == 0)
    rows, index = empty.within(np.array([[0.0, 0.0]]), 5.0)
    assert len(rows) == 0 and len(index) == 0
    grid = PointGrid(np.array([[0.0, 0.0], [1.0, 0.0]]))
    dist, index = grid.nearest(np.zeros((0, 2)))
    assert dist.shape == (0,) and index.shape == (0,)
    rows, index = grid.within(np.zeros((0, 2)), 1.0)
    assert len(rows) == 0 and len(index) == 0


def test_one_point_and_the_bound_is_strict_as_in_a_kd_tree() -> None:
    grid = PointGrid(np.array([[3.0, 4.0]]))
    dist, index = grid.nearest(np.array([[0.0, 0.0], [3.0, 4.0]]))
    np.testing.assert_allclose(dist, [5.0, 0.0])
    assert list(index) == [0, 0]
    dist, index = grid.nearest(np.array([[0.0, 0.0]]), upper_bound=5.0)  # strictly closer only
    assert np.isinf(dist[0]) and index[0] == 1
    dist, index = grid.nearest(np.array([[0.0, 0.0]]), upper_bound=5.0 + 1e-9)
    assert dist[0] == pytest.approx(5.0) and index[0] == 0
    rows, index = grid.within(np.array([[0.0, 0.0]]), 5.0)  # a radius is inclusive
    assert list(rows) == [0] and list(index) == [0]


def test_duplicates_all_come_back_in_a_radius() -> None:
    pts = np.array([[1.0, 1.0]] * 5 + [[2.0, 2.0]] * 40)
    rows, index = PointGrid(pts).within(np.array([[1.0, 1.0], [2.0, 2.0]]), 0.0)
    assert list(rows) == [0] * 5 + [1] * 40
    assert list(index) == list(range(45))


def test_non_finite_input_is_refused() -> None:
    with pytest.raises(ValueError):
        PointGrid(np.array([[0.0, np.nan]]))
    grid = PointGrid(np.array([[0.0, 0.0], [1.0, 1.0]]))
    with pytest.raises(ValueError):
        grid.nearest(np.array([[np.inf, 0.0]]))
    with pytest.raises(ValueError):
        grid.within(np.array([[np.nan, 0.0]]), 1.0)
