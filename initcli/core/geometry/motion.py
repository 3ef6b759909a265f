"""The odometry motion model's decomposition of a move: (rot1, trans, rot2).

The motion between two poses as a turn toward the new position, a straight translation and a
final turn (probabilistic robotics' odometry model, as AMCL uses it). The simulated robot draws
its odometry noise on these three, and the particle filters (Eq. 18, AMCL) predict with them.

:func:`carry_covariance` grows a pose's covariance along an odometry path with the same model,
linearised (the EKF prediction of probabilistic robotics, Table 5.6/7.2: Sigma' = G Sigma G^T +
V M V^T): how the pose verified at a claim is sent later, once the robot has moved on.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from initcli.core.geometry.se2 import Pose2D, wrap_angle

__all__ = ["Alphas", "apply_delta", "carry_covariance", "motion_delta"]


class Alphas(Protocol):
    """The odometry model's noise (AMCL's alpha1..alpha4, e.g. particle_filter.FilterNoise)."""

    @property
    def alpha1(self) -> float: ...
    @property
    def alpha2(self) -> float: ...
    @property
    def alpha3(self) -> float: ...
    @property
    def alpha4(self) -> float: ...


def motion_delta(a: Pose2D, b: Pose2D) -> tuple[float, float, float]:
    """The (rot1 rad, trans m, rot2 rad) decomposition of the motion from ``a`` to ``b``."""
    dx, dy = b.x - a.x, b.y - a.y
    trans = math.hypot(dx, dy)
    rot1 = float(wrap_angle(math.atan2(dy, dx) - a.yaw)) if trans > 1e-6 else 0.0
    # Driving backwards: express as a backward translation rather than a half turn.
    if abs(rot1) > math.pi / 2:
        rot1 = float(wrap_angle(rot1 - math.pi))
        trans = -trans
    rot2 = float(wrap_angle(b.yaw - a.yaw - rot1))
    return rot1, trans, rot2


def apply_delta(pose: Pose2D, rot1: float, trans: float, rot2: float) -> Pose2D:
    """``pose`` moved by (rot1 rad, trans m, rot2 rad): the inverse of :func:`motion_delta`."""
    heading = pose.yaw + rot1
    return Pose2D(
        pose.x + trans * math.cos(heading),
        pose.y + trans * math.sin(heading),
        float(wrap_angle(heading + rot2)),
    )


def carry_covariance(cov: np.ndarray, path: Sequence[Pose2D], noise: Alphas) -> np.ndarray:
    """The 3x3 (x, y, yaw) map-frame covariance of the pose at ``path[0]`` carried along ``path``
    (the robot's odometry poses taken into the map frame) to ``path[-1]``: per step
    G Sigma G^T + V M V^T with M = diag(a1 rot1^2 + a2 trans^2, a3 trans^2 + a4 (rot1^2 + rot2^2),
    a1 rot2^2 + a2 trans^2)."""
    sigma = np.asarray(cov, dtype=float).reshape(3, 3).copy()
    for a, b in zip(path[:-1], path[1:], strict=True):
        rot1, trans, rot2 = motion_delta(a, b)
        heading = a.yaw + rot1
        c, s = math.cos(heading), math.sin(heading)
        g = np.array([[1.0, 0.0, -trans * s], [0.0, 1.0, trans * c], [0.0, 0.0, 1.0]])
        v = np.array([[-trans * s, c, 0.0], [trans * c, s, 0.0], [1.0, 0.0, 1.0]])
        m = np.diag(
            [
                noise.alpha1 * rot1**2 + noise.alpha2 * trans**2,
                noise.alpha3 * trans**2 + noise.alpha4 * (rot1**2 + rot2**2),
                noise.alpha1 * rot2**2 + noise.alpha2 * trans**2,
            ]
        )
        sigma = g @ sigma @ g.T + v @ m @ v.T
    out: np.ndarray = (sigma + sigma.T) / 2
    return out
