"""AMCL global localisation (§4.3 baseline, Eq. 18 from a uniform prior, KLD-sampling) on hand-made grids."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from initcli.core.filters.global_localisation import (
    GlobalLocalisation,
    GlobalLocalisationParams,
    PoseHistogram,
    free_cell_centres,
    kld_sample_limit,
    low_variance_indices,
)
from initcli.core.geometry.motion import apply_delta, motion_delta
from initcli.core.geometry.se2 import Pose2D, wrap_angle

RES = 0.05


RANGE_MAX = 10.0


BEAM_ANGLES = -math.pi + 2 * math.pi / 180 * np.arange(180)


def room_grid(inside: np.ndarray) -> OccupancyGrid:
    """Free cells where ``inside`` (row 0 = top), 2-cell walls around them, unknown beyond."""
    padded = np.pad(inside, 3)
    near = np.zeros_like(padded)
    for dr in range(-2, 3):
        for dc in range(-2, 3):
            near |= np.roll(np.roll(padded, dr, axis=0), dc, axis=1)
    cells = np.full(padded.shape, UNKNOWN, dtype=np.uint8)
    cells[near & ~padded] = OCCUPIED
    cells[padded] = FREE
    return OccupancyGrid(cells, RES, (-3 * RES, -3 * RES, 0.0))


def l_room() -> OccupancyGrid:
    """6 m x 4 m with the top-right 3 m x 2 m cut away: no symmetry."""
    rows, cols = round(4 / RES), round(6 / RES)
    inside = np.ones((rows, cols), dtype=bool)
    inside[: rows // 2, cols // 2 :] = False
    return room_grid(inside)


def rectangle_room() -> OccupancyGrid:
    """A plain 6 m x 3 m rectangle: a half turn about its centre maps it onto itself."""
    return room_grid(np.ones((round(3 / RES), round(6 / RES)), dtype=bool))


def simulated_scan(grid: OccupancyGrid, pose: Pose2D) -> np.ndarray:
    """Ranges of BEAM_ANGLES from ``pose`` by marching 1 cm steps to the first occupied cell."""
    r = np.arange(0.01, RANGE_MAX, 0.01)
    heading = pose.yaw + BEAM_ANGLES[:, None]
    x, y = pose.x + r * np.cos(heading), pose.y + r * np.sin(heading)
    row, col = grid.world_to_cell(x, y)
    inside = (row >= 0) & (row < grid.shape[0]) & (col >= 0) & (col < grid.shape[1])
    hit = np.zeros(x.shape, dtype=bool)
    hit[inside] = grid.cells[row[inside], col[inside]] == OCCUPIED
    first = np.argmax(hit, axis=1)
    return np.where(hit.any(axis=1), r[first], RANGE_MAX)


def drive(
    amcl: GlobalLocalisation, grid: OccupancyGrid, poses: list[Pose2D]
) -> tuple[list[int], list[float]]:
    """Feed exact odometry and simulated scans along ``poses``; particle counts and x/y variances."""
    counts, variances = [amcl.count], []
    amcl.update(BEAM_ANGLES, simulated_scan(grid, poses[0]), RANGE_MAX)
    counts.append(amcl.count)
    for a, b in zip(poses, poses[1:], strict=False):
        amcl.predict(motion_delta(a, b))
        amcl.update(BEAM_ANGLES, simulated_scan(grid, b), RANGE_MAX)
        counts.append(amcl.count)
        cov = amcl.whole_covariance()
        variances.append(float(max(cov[0, 0], cov[1, 1])))
    return counts, variances


def path(start: Pose2D, moves: list[tuple[float, float, float]]) -> list[Pose2D]:
    poses = [start]
    for move in moves:
        poses.append(apply_delta(poses[-1], *move))
    return poses


# Along the bottom of the L, then up its left arm: 0.25 m steps (update_min_d).
L_PATH = path(Pose2D(4.5, 1.0, math.pi), [(0.0, 0.25, 0.0)] * 12)


def test_kld_limit_follows_fox_and_is_clamped() -> None:
    params = GlobalLocalisationParams()
    k = np.array([0, 1, 2, 10, 50, 100, 10_000])
    n = kld_sample_limit(k, params)
    assert n[0] == n[1] == params.min_particles
    b = 2 / (9 * 49)
    assert n[4] == math.ceil(49 / (2 * 0.01) * (1 - b + math.sqrt(b) * 0.99) ** 3)  # 2936
    assert n[5] == n[6] == params.particles
    assert np.all(np.diff(n) >= 0)


def test_low_variance_indices_draws_any_count_in_proportion() -> None:
    rng = np.random.default_rng(0)
    weights = np.array([0.5, 0.0, 0.25, 0.25])
    idx = low_variance_indices(weights, 400, rng)
    assert len(idx) == 400
    assert np.bincount(idx, minlength=4).tolist() == [200, 0, 100, 100]
    assert low_variance_indices(weights, 3, rng).max() <= 3


def test_clusters_join_neighbouring_bins_and_wrap_heading() -> None:
    histogram = PoseHistogram(l_room(), 0.5, math.radians(10))
    rng = np.random.default_rng(1)
    near_pi = np.column_stack(
        [rng.normal(1.0, 0.1, 100), rng.normal(1.0, 0.1, 100), np.full(100, math.pi - 0.01)]
    )
    near_pi[::2, 2] = -math.pi + 0.01  # the same heading, either side of the wrap
    far = np.column_stack([rng.normal(4.0, 0.1, 100), rng.normal(1.0, 0.1, 100), np.zeros(100)])
    labels = histogram.clusters(np.vstack([near_pi, far]))
    assert len(set(labels[:100].tolist())) == 1
    assert len(set(labels[100:].tolist())) == 1
    assert labels[0] != labels[100]


def test_particles_start_uniform_over_free_cells() -> None:
    grid = l_room()
    amcl = GlobalLocalisation(grid, GlobalLocalisationParams(), np.random.default_rng(2))
    assert amcl.count == 5000
    assert amcl.particles.dtype == np.float32
    rows, cols = grid.world_to_cell(amcl.particles[:, 0], amcl.particles[:, 1])
    assert np.all(grid.cells[rows, cols] == FREE)
    assert len(free_cell_centres(grid)) == int((grid.cells == FREE).sum())
    # Both arms of the L get particles in proportion to their area; headings cover the circle.
    assert 0.2 < np.mean(amcl.particles[:, 1] > 2.0) < 0.45
    assert np.histogram(amcl.particles[:, 2], bins=4, range=(-math.pi, math.pi))[0].min() > 1000


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_converges_to_the_true_pose_in_an_asymmetric_room(seed: int) -> None:
    grid = l_room()
    params = GlobalLocalisationParams()
    amcl = GlobalLocalisation(grid, params, np.random.default_rng(seed))
    counts, variances = drive(amcl, grid, L_PATH)
    estimate = amcl.estimate()
    truth = L_PATH[-1]
    assert estimate.pose.distance_to(truth) < 0.2
    assert estimate.pose.yaw_error(truth) < math.radians(5)
    assert variances[-1] < 0.01  # below the fine-tuning threshold: the baseline would claim here
    # KLD: from the 5000 uniform particles down to the minimum for a compact cloud, never outside.
    assert counts[0] == params.particles
    assert all(params.min_particles <= c <= params.particles for c in counts)
    assert counts[-1] < 0.2 * params.particles
    assert estimate.clusters == 1 and estimate.cluster_weight == pytest.approx(1.0)


def test_fixed_count_keeps_every_particle() -> None:
    grid = l_room()
    params = GlobalLocalisationParams(particles=2000, kld=False)
    amcl = GlobalLocalisation(grid, params, np.random.default_rng(6))
    counts, _ = drive(amcl, grid, L_PATH[:6])
    assert counts == [2000] * len(counts)


def test_a_symmetric_room_converges_to_either_symmetric_pose() -> None:
    """In a rectangle the scan from (x, y, yaw) equals the scan from its half turn about the centre.

    Resampling at every update collapses the cloud onto one of the two poses, picked by chance:
    the wrong localisation in repetitive environments the paper reports for AMCL (§4.3, Fig. 13a).
    """
    grid = rectangle_room()
    truth = path(Pose2D(1.5, 0.8, 0.0), [(0.0, 0.25, 0.0)] * 12)[-1]
    mirror = Pose2D(6.0 - truth.x, 3.0 - truth.y, float(wrap_angle(truth.yaw + math.pi)))
    picked = []
    for seed in range(7, 15):
        amcl = GlobalLocalisation(grid, GlobalLocalisationParams(), np.random.default_rng(seed))
        drive(amcl, grid, path(Pose2D(1.5, 0.8, 0.0), [(0.0, 0.25, 0.0)] * 12))
        pose = amcl.estimate().pose
        at_truth = pose.distance_to(truth) < 0.2 and pose.yaw_error(truth) < math.radians(5)
        at_mirror = pose.distance_to(mirror) < 0.2 and pose.yaw_error(mirror) < math.radians(5)
        assert at_truth or at_mirror
        picked.append(at_truth)
    assert any(picked) and not all(picked)
