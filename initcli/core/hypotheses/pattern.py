"""Feature-pattern geometry shared by matching (Algorithm 1) and the cost (Eq. 14): Eq. 5, 6, 8.

All functions are vectorised over leading dimensions: points are arrays of shape (..., 2).
"""

from __future__ import annotations

import numpy as np

__all__ = ["angle_difference", "pair_distance", "rotation_angle"]


def pair_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Eq. 5: d_uv = sqrt((x_v - x_u)^2 + (y_v - y_u)^2)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    distance: np.ndarray = np.hypot(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1])  # Eq. 5
    return distance


def rotation_angle(u: np.ndarray, v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Eq. 8: theta_uvw, the signed rotation from direction v_uv to direction v_uw, in (-pi, pi].

    The direction vectors of Eq. 6 are unit vectors; atan2 of (cross, dot) does not depend on
    their length, so the unnormalised differences are used (same angle, no division by zero).
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    ax, ay = v[..., 0] - u[..., 0], v[..., 1] - u[..., 1]  # Eq. 6 (times d_uv)
    bx, by = w[..., 0] - u[..., 0], w[..., 1] - u[..., 1]  # Eq. 6 (times d_uw)
    theta: np.ndarray = np.arctan2(ax * by - ay * bx, ax * bx + ay * by)  # Eq. 8
    return theta


def angle_difference(a: np.ndarray | float, b: np.ndarray | float) -> np.ndarray:
    """|a - b| for angles, wrapped to [0, pi].

    The paper writes |theta_uvw - theta_ijk| (Eq. 9, 14); taken literally it would call 179 deg and
    -179 deg 358 deg apart, which rejects the true match whenever three features are nearly
    collinear with the third behind the first (a robot turning round in a corridor). The wrapped
    difference is the only deviation from the published criteria, and the oracle uses it too.
    """
    d = np.abs(np.asarray(a, dtype=float) - np.asarray(b, dtype=float)) % (2.0 * np.pi)
    wrapped: np.ndarray = np.minimum(d, 2.0 * np.pi - d)
    return wrapped
