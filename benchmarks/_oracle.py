"""A plain transcription of the paper's Algorithm 1: the oracle for the indexed matcher.

:func:`algorithm1` follows the published pseudocode line by line (loops over all of B, Eq. 5-9
evaluated with ``math``), with the angle difference wrapped as documented in
:func:`initcli.core.hypotheses.pattern.angle_difference`. :func:`algorithm1_with_outliers` applies it to every
subsequence of S that leaves out at most ``max_outliers`` features -- the definition of outlier
tolerance in :mod:`initcli.core.hypotheses.matching`.
``tests/initcli/core/hypotheses/test_matching.py`` checks the
indexed matcher against both; ``benchmarks/bench_match.py`` reports the speed ratio.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from initcli.core.hypotheses.matching import OUTLIER

__all__ = ["algorithm1", "algorithm1_with_outliers"]


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
