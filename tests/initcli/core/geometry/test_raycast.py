"""The fast lidar ray cast (:func:`cast_rays`) against the brute force :func:`ray_segment_distances` kept
as the reference: random worlds, awkward segments, other angle sets, small and empty inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.raycast import cast_rays, nearest_segment_distance, ray_segment_distances
from initcli.sim.driver import LidarSpec

LIDAR = LidarSpec()


LIDAR_ANGLES = LIDAR.angle_min + LIDAR.angle_increment * np.arange(LIDAR.beams)


def assert_same(origin: np.ndarray, angles: np.ndarray, segments: np.ndarray, max_range: float) -> None:
    """cast_rays == the brute force, bit for bit (the compiled loops compute the same float64
    expressions in the same order)."""
    expected = ray_segment_distances(origin, angles, segments, max_range)
    np.testing.assert_array_equal(cast_rays(origin, angles, segments, max_range), expected)


def random_segments(rng: np.random.Generator, n: int, span: float) -> np.ndarray:
    """Walls: a mix of axis-aligned and arbitrary segments of 0.05-8 m, some zero-length."""
    a = rng.uniform(-span, span, (n, 2))
    angle = np.where(rng.random(n) < 0.5, rng.integers(0, 4, n) * math.pi / 2, rng.uniform(0, 2 * math.pi, n))
    length = rng.uniform(0.05, 8.0, n) * (rng.random(n) > 0.02)
    b = a + length[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    return np.column_stack([a, b])


def awkward_groups(rng: np.random.Generator, origin: np.ndarray, angles: np.ndarray) -> list[np.ndarray]:
    """Groups of segments to test one group at a time (a segment through the origin hides all else):
    through or next to the origin, collinear with it, ending exactly on rays, at the range's edge."""
    groups = []
    for off in (0.0, 1e-12, 1e-6, 1e-4, 9e-4, 2e-3, 0.05):
        phi = rng.uniform(0, 2 * math.pi)
        d = np.array([math.cos(phi), math.sin(phi)])
        n = np.array([-d[1], d[0]])
        lo, hi = rng.uniform(-3, -0.01), rng.uniform(0.01, 3)
        if off > 1e-3:
            lo, hi = sorted(rng.choice([lo, hi, rng.uniform(-3, 3), 0.0], 2, replace=False))
        groups.append(np.array([[*(origin + off * n + lo * d), *(origin + off * n + hi * d)]]))
    phi = rng.uniform(0, 2 * math.pi, 10)
    d = np.column_stack([np.cos(phi), np.sin(phi)])
    r0, r1 = rng.uniform(0.5, 15, (2, 10, 1))
    groups.append(np.column_stack([origin + r0 * d, origin + (r0 + r1) * d]))  # collinear, beyond
    k = rng.integers(0, len(angles), 20)
    r = rng.uniform(0.3, 19.0, (20, 1))
    ends = origin + r * np.column_stack([np.cos(angles[k]), np.sin(angles[k])])
    k2 = (k + rng.integers(1, 40, 20)) % len(angles)
    ends2 = origin + r * np.column_stack([np.cos(angles[k2]), np.sin(angles[k2])])
    groups.append(np.column_stack([ends, ends2]))  # endpoints exactly on rays
    groups.append(np.column_stack([ends2, ends]))
    edge = [[*(origin + [rr, -1.0]), *(origin + [rr, 1.0])] for rr in (19.9999999, 20.0, 20.0000001, 20.5)]
    groups.append(np.array(edge))  # at the edge of the range
    return groups


@pytest.mark.parametrize("seed", range(8))
def test_lidar_scans_on_random_worlds(seed: int) -> None:
    rng = np.random.default_rng(seed)
    segments = random_segments(rng, 600, 25.0)
    for _ in range(15):
        origin = rng.uniform(-20, 20, 2)
        angles = LIDAR_ANGLES + rng.uniform(-4 * math.pi, 4 * math.pi)
        assert_same(origin, angles, segments, 20.0)
    for _ in range(15):
        origin = rng.uniform(-20, 20, 2)
        angles = LIDAR_ANGLES + rng.uniform(-4 * math.pi, 4 * math.pi)
        for group in awkward_groups(rng, origin, angles):
            assert_same(origin, angles, group, 20.0)
            assert_same(origin, angles, np.concatenate([segments[:50], group]), 20.0)


@pytest.mark.parametrize("seed", range(4))
def test_other_angle_sets(seed: int) -> None:
    """Uneven, unsorted, partial, repeated and huge angles take the binary-search path."""
    rng = np.random.default_rng(100 + seed)
    segments = random_segments(rng, 400, 15.0)
    origin = rng.uniform(-10, 10, 2)
    cases = [
        rng.uniform(-math.pi, math.pi, 500),
        np.sort(rng.uniform(0, 7 * math.pi, 300)),
        np.linspace(-1.0, 1.0, 181),  # a 115 degree fan
        LIDAR_ANGLES[::-1].copy(),
        np.repeat(LIDAR_ANGLES[:90], 3),
        LIDAR_ANGLES + 1e4,
        np.array([0.3, 0.3 + 1e-13, 2.0]),
    ]
    for angles in cases:
        assert_same(origin, angles, segments, 12.0)
        for group in awkward_groups(rng, origin, angles):
            assert_same(origin, angles, group, 20.0)


def test_small_and_empty_inputs() -> None:
    origin = np.array([0.5, -0.25])
    segments = np.array([[2.0, -1.0, 2.0, 1.0], [-1.0, 3.0, 1.0, 3.0]])
    assert_same(origin, np.array([0.0]), segments, 5.0)
    assert_same(origin, LIDAR_ANGLES, segments, 5.0)
    assert cast_rays(origin, LIDAR_ANGLES, np.zeros((0, 4)), 5.0).tolist() == [5.0] * LIDAR.beams
    assert cast_rays(origin, np.zeros(0), segments, 5.0).shape == (0,)
    far = np.array([[100.0, -1.0, 100.0, 1.0]] * 50)
    assert cast_rays(origin, LIDAR_ANGLES, far, 5.0).tolist() == [5.0] * LIDAR.beams


def test_nearest_segment_distance_is_the_projection_formula() -> None:
    """The compiled loop against the numpy form it replaced (clip the projection to the segment,
    measure to that point), on random segments with some of zero length, capped."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        segments = rng.uniform(-5, 5, (int(rng.integers(1, 40)), 4))
        dot = rng.random(len(segments)) < 0.05
        segments[dot, 2:4] = segments[dot, 0:2]
        p = rng.uniform(-5, 5, 2)
        a, ab = segments[:, 0:2], segments[:, 2:4] - segments[:, 0:2]
        s = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-9), 0, 1)
        expected = min(1.0, float(np.hypot(*(a + ab * s[:, None] - p).T).min()))
        got = nearest_segment_distance(float(p[0]), float(p[1]), segments, 1.0)
        assert got == pytest.approx(expected, rel=0, abs=1e-12)
    assert nearest_segment_distance(0.0, 0.0, np.zeros((0, 4)), 0.8) == 0.8
    assert nearest_segment_distance(0.0, 0.0, np.array([[3.0, -1.0, 3.0, 1.0]]), 5.0) == 3.0


def test_without_numba_the_loops_give_the_same_scans(monkeypatch: pytest.MonkeyPatch) -> None:
    """numba is the [fast] extra: the loops run as plain Python without it, bit for bit the same."""
    from initcli.core.geometry import raycast

    for name in ("_cast_turn", "_nearest_hits", "_shorten", "nearest_segment_distance"):
        loop = getattr(raycast, name)
        monkeypatch.setattr(raycast, name, getattr(loop, "py_func", loop))
    rng = np.random.default_rng(7)
    segments = random_segments(rng, 120, 10.0)
    origin = rng.uniform(-5, 5, 2)
    assert_same(origin, LIDAR_ANGLES, segments, 12.0)  # a full turn of even beams
    assert_same(origin, rng.uniform(-math.pi, math.pi, 50), segments, 12.0)  # the sorted runs
