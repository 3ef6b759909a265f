"""A plain transcription of the paper's Algorithm 1, used as the oracle for the indexed matcher.

:func:`algorithm1` follows the published pseudocode line by line (loops over all of B, Eq. 5-9
evaluated with ``math``), with the angle difference wrapped as documented in
:func:`initcli.core.pattern.angle_difference`. :func:`algorithm1_with_outliers` applies it to every
subsequence of S that leaves out at most ``max_outliers`` features -- the definition of outlier
tolerance in :mod:`initcli.core.matching`. ``benchmarks/bench_match.py`` imports both to report the
speed ratio.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import pytest

from initcli.core.cost import matching_cost
from initcli.core.matching import OUTLIER, BimIndex, Matcher, MatchParams
from initcli.match.pipeline import MatchOptions

# The literal Algorithm 1 (no revisits) with the tool's default thresholds.
LITERAL = MatchOptions(revisits=False).match_params()


def _dist(p: Sequence[float], q: Sequence[float]) -> float:
    return math.sqrt((q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2)  # Eq. 5


def _theta(p: Sequence[float], q: Sequence[float], r: Sequence[float]) -> float:
    d_pq, d_pr = _dist(p, q), _dist(p, r)
    vx, vy = (q[0] - p[0]) / d_pq, (q[1] - p[1]) / d_pq  # Eq. 6
    wx, wy = (r[0] - p[0]) / d_pr, (r[1] - p[1]) / d_pr  # Eq. 6
    return math.atan2(vx * wy - vy * wx, vx * wx + vy * wy)  # Eq. 8


def _angle_diff(a: float, b: float) -> float:
    d = abs(a - b) % (2 * math.pi)
    return min(d, 2 * math.pi - d)


def algorithm1(
    b_xy: Sequence[Sequence[float]],
    b_cls: Sequence[str],
    s_xy: Sequence[Sequence[float]],
    s_cls: Sequence[str],
    alpha: float,
    beta: float,
) -> list[tuple[int, ...]]:
    """Algorithm 1 of the paper, literally. Returns the set M of complete matches (index tuples)."""
    n_s, n_b = len(s_xy), len(b_xy)

    def z_d(i: int, u: int, j: int, v: int) -> bool:  # Eq. 7
        return abs(_dist(b_xy[u], b_xy[v]) - _dist(s_xy[i], s_xy[j])) <= alpha

    def z(i: int, u: int, j: int, v: int, k: int, w: int) -> bool:  # Eq. 9
        if not (z_d(i, u, j, v) and z_d(i, u, k, w)):
            return False
        return _angle_diff(_theta(b_xy[u], b_xy[v], b_xy[w]), _theta(s_xy[i], s_xy[j], s_xy[k])) <= beta

    M: list[tuple[int, ...]] = []
    if n_s < 2:
        return M
    for u in range(n_b):  # line 1
        if b_cls[u] != s_cls[0]:
            continue
        M_u: list[tuple[int, ...]] = []  # line 2
        for v in range(n_b):  # line 3
            if v != u and b_cls[v] == s_cls[1] and z_d(0, u, 1, v):  # line 4
                M_u.append((u, v))
        for i in range(2, n_s):  # line 7
            E: list[tuple[int, ...]] = []
            for m in M_u:  # line 8
                for w in range(n_b):
                    if w in m:  # w not matched with any feature in S_object
                        continue
                    if b_cls[w] == s_cls[i] and z(i - 2, m[i - 2], i - 1, m[i - 1], i, w):  # line 9
                        E.append((*m, w))
            M_u = E  # line 12
        M.extend(M_u)  # line 14
    return M


def algorithm1_with_outliers(
    b_xy: Sequence[Sequence[float]],
    b_cls: Sequence[str],
    s_xy: Sequence[Sequence[float]],
    s_cls: Sequence[str],
    alpha: float,
    beta: float,
    max_outliers: int,
    min_inliers: int,
    min_inliers_outlier: int = 2,
) -> set[tuple[int, ...]]:
    """Algorithm 1 on every subsequence of S leaving out at most ``max_outliers`` features; a full match
    needs ``min_inliers`` features, one with outliers ``min_inliers_outlier``."""
    n = len(s_xy)
    out: set[tuple[int, ...]] = set()
    for k in range(0, max_outliers + 1):
        for dropped in itertools.combinations(range(n), k):
            keep = [i for i in range(n) if i not in dropped]
            if len(keep) < max(2, min_inliers if k == 0 else min_inliers_outlier):
                continue
            for m in algorithm1(b_xy, b_cls, [s_xy[i] for i in keep], [s_cls[i] for i in keep], alpha, beta):
                full = [OUTLIER] * n
                for i, b in zip(keep, m, strict=True):
                    full[i] = b
                out.add(tuple(full))
    return out


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
