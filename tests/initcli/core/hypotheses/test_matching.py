"""The indexed matcher against the plain transcription of the paper's Algorithm 1 in
``benchmarks/_oracle.py`` (:func:`algorithm1`, and :func:`algorithm1_with_outliers` for outlier
tolerance): the same set of matches on random cases, lattices and rigid motions.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from benchmarks._oracle import algorithm1, algorithm1_with_outliers
from initcli.core.hypotheses.cost import matching_cost
from initcli.core.hypotheses.matching import OUTLIER, BimIndex, Matcher, MatchParams
from initcli.match.pipeline import MatchOptions

# The literal Algorithm 1 (no revisits) with the tool's default thresholds.
LITERAL = MatchOptions(revisits=False).match_params()


def random_case(rng: np.random.Generator, n_b: int, n_s: int, noise: float, extent: float = 30.0):
    """BIM features at random, S = a noisy, rigidly moved sequence of some of them (+ maybe a stray one)."""
    classes = np.array(["door", "lift", "stairs"])
    b_xy = rng.uniform(0, extent, size=(n_b, 2))
    b_cls = list(rng.choice(classes, size=n_b, p=[0.8, 0.1, 0.1]))
    chosen = rng.choice(n_b, size=n_s, replace=False)
    yaw = rng.uniform(-math.pi, math.pi)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    s_xy = (b_xy[chosen] @ rot.T) + rng.uniform(-50, 50, 2) + rng.normal(0, noise, (n_s, 2))
    s_cls = [b_cls[i] for i in chosen]
    if rng.random() < 0.3:  # a stray detection somewhere in the sequence
        pos = int(rng.integers(0, n_s + 1))
        s_xy = np.insert(s_xy, pos, s_xy.mean(axis=0) + rng.normal(0, 5, 2), axis=0)
        s_cls.insert(pos, "door")
    return b_xy, b_cls, s_xy, s_cls


def indexed_matches(b_xy, b_cls, s_xy, s_cls, params: MatchParams) -> set[tuple[int, ...]]:
    matcher = Matcher(BimIndex(np.asarray(b_xy), b_cls), params)
    state = matcher.match(np.asarray(s_xy), s_cls)
    rows = state.matches(params)
    return {tuple(int(a) for a in row) for row in state.assign[rows]}


@pytest.mark.parametrize("seed", range(40))
def test_indexed_matcher_equals_algorithm1(seed: int) -> None:
    rng = np.random.default_rng(seed)
    b_xy, b_cls, s_xy, s_cls = random_case(rng, int(rng.integers(15, 60)), int(rng.integers(2, 6)), noise=0.1)
    alpha, beta = float(rng.uniform(0.3, 1.5)), math.radians(float(rng.uniform(5, 40)))
    oracle = set(algorithm1(b_xy.tolist(), b_cls, s_xy.tolist(), s_cls, alpha, beta))
    params = MatchParams(alpha=alpha, beta=beta, max_outliers=0, min_inliers=2, revisits=False)
    assert indexed_matches(b_xy, b_cls, s_xy, s_cls, params) == oracle


@pytest.mark.parametrize("seed", range(25))
def test_indexed_matcher_with_outliers_equals_oracle(seed: int) -> None:
    rng = np.random.default_rng(1000 + seed)
    b_xy, b_cls, s_xy, s_cls = random_case(rng, int(rng.integers(15, 40)), int(rng.integers(3, 6)), noise=0.1)
    alpha, beta = float(rng.uniform(0.3, 1.2)), math.radians(float(rng.uniform(5, 30)))
    k = int(rng.integers(1, 3))
    min_inliers = int(rng.integers(2, 4))
    oracle = algorithm1_with_outliers(b_xy.tolist(), b_cls, s_xy.tolist(), s_cls, alpha, beta, k, min_inliers)
    params = MatchParams(alpha=alpha, beta=beta, max_outliers=k, min_inliers=min_inliers, revisits=False)
    assert indexed_matches(b_xy, b_cls, s_xy, s_cls, params) == oracle


def test_accumulated_cost_equals_eq14() -> None:
    rng = np.random.default_rng(7)
    b_xy, b_cls, s_xy, s_cls = random_case(rng, 40, 5, noise=0.15)
    params = MatchParams(alpha=1.0, beta=math.radians(30), max_outliers=1, min_inliers=3, revisits=False)
    matcher = Matcher(BimIndex(b_xy, b_cls), params)
    state = matcher.match(s_xy, s_cls)
    rows = state.matches(params)
    assert len(rows) > 0
    for r in rows:
        inl = np.flatnonzero(state.assign[r] != OUTLIER)
        expected = matching_cost(b_xy[state.assign[r, inl]], s_xy[inl])  # Eq. 14 over the inliers
        assert state.cost[r] == pytest.approx(expected, abs=1e-9)


def test_true_match_is_found_under_any_rigid_motion() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        b_xy, b_cls, s_xy, s_cls = random_case(rng, 50, 5, noise=0.0)
        found = indexed_matches(b_xy, b_cls, s_xy, s_cls, LITERAL)
        assert found, "the noise-free true match must survive"


@pytest.mark.parametrize("seed", range(12))
def test_repetitive_lattice_equals_algorithm1(seed: int) -> None:
    # doors on a regular lattice (the worst case for ambiguity); the walk may turn back, so consecutive
    # triples are nearly collinear with angles near +-180 deg (the wrapped angle difference matters)
    rng = np.random.default_rng(500 + seed)
    gx, gy = np.meshgrid(np.arange(8) * 4.0, np.arange(3) * 2.0)
    b_xy = np.column_stack([gx.ravel(), gy.ravel()]) + rng.normal(0, 0.05, (gx.size, 2))
    b_cls = ["door"] * len(b_xy)
    b_cls[int(rng.integers(len(b_cls)))] = "lift"
    walk = [int(rng.integers(len(b_xy)))]
    while len(walk) < 5:
        nxt = int(rng.integers(len(b_xy)))
        if nxt not in walk and np.hypot(*(b_xy[nxt] - b_xy[walk[-1]])) < 9:
            walk.append(nxt)
    yaw = rng.uniform(-math.pi, math.pi)
    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    s_xy = b_xy[walk] @ rot.T + rng.normal(0, 0.1, (5, 2))
    s_cls = [b_cls[i] for i in walk]
    alpha, beta = 0.5, math.radians(15)
    oracle = set(algorithm1(b_xy.tolist(), b_cls, s_xy.tolist(), s_cls, alpha, beta))
    assert tuple(walk) in oracle
    params = MatchParams(alpha=alpha, beta=beta, max_outliers=0, min_inliers=2, revisits=False)
    assert indexed_matches(b_xy, b_cls, s_xy, s_cls, params) == oracle
    k1 = algorithm1_with_outliers(b_xy.tolist(), b_cls, s_xy.tolist(), s_cls, alpha, beta, 1, 3)
    assert indexed_matches(b_xy, b_cls, s_xy, s_cls, replace(params, max_outliers=1, min_inliers=3)) == k1


@pytest.mark.parametrize("seed", range(10))
def test_matches_are_invariant_under_rigid_motions_of_the_detections(seed: int) -> None:
    rng = np.random.default_rng(900 + seed)
    b_xy, b_cls, s_xy, s_cls = random_case(rng, 60, 5, noise=0.1)
    params = MatchParams(alpha=0.8, beta=math.radians(25), max_outliers=1, min_inliers=3, revisits=False)
    base = indexed_matches(b_xy, b_cls, s_xy, s_cls, params)
    for _ in range(5):
        yaw = rng.uniform(-math.pi, math.pi)
        rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
        moved = s_xy @ rot.T + rng.uniform(-1e4, 1e4, 2)
        assert indexed_matches(b_xy, b_cls, moved, s_cls, params) == base
