"""The matching cost J (Eq. 14) that ranks hypotheses.

J sums the same quantities Algorithm 1 thresholds: the distance error of the first pair, then for
every later feature i the two distance errors and the angle error of the triple (i-2, i-1, i).
Distances are in metres and angles in radians, added as the paper does.

With outlier tolerance the cost is taken over the *inlier* subsequence, exactly as if the
outliers had never been detected (see :mod:`initcli.core.hypotheses.matching`).
"""

from __future__ import annotations

import numpy as np

from initcli.core.hypotheses.pattern import angle_difference, pair_distance, rotation_angle

__all__ = ["matching_cost", "pair_cost", "triple_cost"]


def pair_cost(b_u: np.ndarray, b_v: np.ndarray, s_i: np.ndarray, s_j: np.ndarray) -> np.ndarray:
    """First term of Eq. 14: |d^B_{m(s1)m(s2)} - d^S_{s1 s2}|."""
    cost: np.ndarray = np.abs(pair_distance(b_u, b_v) - pair_distance(s_i, s_j))
    return cost


def triple_cost(
    b_u: np.ndarray, b_v: np.ndarray, b_w: np.ndarray, s_i: np.ndarray, s_j: np.ndarray, s_k: np.ndarray
) -> np.ndarray:
    """One summand of Eq. 14 for the triple (s_{i-2}, s_{i-1}, s_i) matched to (b_u, b_v, b_w)."""
    cost: np.ndarray = (
        np.abs(pair_distance(b_u, b_v) - pair_distance(s_i, s_j))  # |d^B_{uv} - d^S_{i-2,i-1}|
        + np.abs(pair_distance(b_u, b_w) - pair_distance(s_i, s_k))  # |d^B_{uw} - d^S_{i-2,i}|
        + angle_difference(rotation_angle(b_u, b_v, b_w), rotation_angle(s_i, s_j, s_k))  # |theta - theta|
    )
    return cost


def matching_cost(b_xy: np.ndarray, s_xy: np.ndarray) -> float:
    """Eq. 14 for one match: ``b_xy[i]`` is m(s_i) for the (inlier) sequence ``s_xy``, both (n, 2).

    Returns 0 for fewer than two features.
    """
    b = np.asarray(b_xy, dtype=float).reshape(-1, 2)
    s = np.asarray(s_xy, dtype=float).reshape(-1, 2)
    n = len(s)
    if n < 2:
        return 0.0
    j = float(pair_cost(b[0], b[1], s[0], s[1]))  # Eq. 14, first term
    if n >= 3:
        j += float(np.sum(triple_cost(b[:-2], b[1:-1], b[2:], s[:-2], s[1:-1], s[2:])))  # Eq. 14, sum i>=3
    return j
