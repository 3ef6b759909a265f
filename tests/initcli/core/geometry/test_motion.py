"""initcli.core.geometry.motion: the odometry model's decomposition, and a covariance carried along a path
(the linearised model against the particle filter's sampled one)."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.filters.particle_filter import FilterNoise, sample_motion
from initcli.core.geometry.motion import apply_delta, carry_covariance, motion_delta
from initcli.core.geometry.se2 import Pose2D, wrap_angle


def _arc(n: int = 40) -> list[Pose2D]:
    """1.6 m at 0.4 m per second, turning 0.3 rad/s: the robot driving on after a claim."""
    return [
        Pose2D(0.4 * math.sin(0.3 * t / 10) / 0.3, 0.4 * (1 - math.cos(0.3 * t / 10)) / 0.3, 0.3 * t / 10)
        for t in range(n)
    ]


def test_delta_round_trip() -> None:
    a, b = Pose2D(1.0, 2.0, 0.3), Pose2D(1.5, 2.4, 0.9)
    again = apply_delta(a, *motion_delta(a, b))
    assert again.distance_to(b) < 1e-9 and again.yaw_error(b) < 1e-9


def test_no_motion_keeps_the_covariance() -> None:
    cov = np.diag([0.01, 0.02, 0.003])
    still = [Pose2D(1.0, 1.0, 0.5)] * 5
    assert np.allclose(carry_covariance(cov, still, FilterNoise()), cov)


def test_the_carried_covariance_grows_as_sampled_motion_spreads() -> None:
    path = _arc()
    cov0 = np.diag([0.0025, 0.0025, 0.0004])
    noise = FilterNoise(0.02, 0.02, 0.02, 0.02)
    carried = carry_covariance(cov0, path, noise)
    assert np.all(np.linalg.eigvalsh(carried - cov0) > -1e-12) and carried[0, 0] > cov0[0, 0]
    assert carried[2, 2] > cov0[2, 2]
    # The same motion sampled for 20000 particles from the start's covariance (Eq. 18's motion model).
    rng = np.random.default_rng(1)
    particles = rng.multivariate_normal(path[0].as_tuple(), cov0, 20000)
    for a, b in zip(path[:-1], path[1:], strict=True):
        particles = sample_motion(particles, motion_delta(a, b), noise, rng)
    centred = particles - np.array(path[-1].as_tuple())
    centred[:, 2] = wrap_angle(centred[:, 2])
    sampled = np.cov(centred.T)
    assert np.allclose(np.diag(carried), np.diag(sampled), rtol=0.15)
    assert abs(carried[0, 1] - sampled[0, 1]) < 0.15 * math.sqrt(sampled[0, 0] * sampled[1, 1])
