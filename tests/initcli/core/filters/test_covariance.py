"""The covariance sent with a fine pose: never below the floor, and as wide as the fine pose and
the coarse claim disagree."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.filters.covariance import honest_covariance
from initcli.core.geometry.se2 import Pose2D


def test_a_tight_cloud_is_floored():
    tight = np.diag([1e-6, 1e-6, 1e-8])
    c = honest_covariance(tight, Pose2D(1, 2, 0.3), Pose2D(1, 2, 0.3), 0.05, 0.5)
    assert math.sqrt(c[0, 0]) >= 0.05 and math.sqrt(c[1, 1]) >= 0.05
    assert math.sqrt(c[2, 2]) >= math.radians(0.5)


def test_disagreement_with_the_claim_widens_it_along_the_difference():
    c = honest_covariance(np.zeros((3, 3)), Pose2D(0.4, 0.0, 0.0), Pose2D(0.0, 0.0, 0.0), 0.0, 0.0)
    assert math.isclose(c[0, 0], 0.16) and c[1, 1] == 0.0
    error = np.array([0.4, 0.0, 0.0])  # the claim was right: the fine pose's error sits on the ellipse
    nees = error @ np.linalg.pinv(c) @ error
    assert nees <= 1.0 + 1e-9
    wrapped = honest_covariance(
        np.zeros((3, 3)), Pose2D(0, 0, math.pi - 0.01), Pose2D(0, 0, -math.pi + 0.01), 0, 0
    )
    assert math.isclose(math.sqrt(wrapped[2, 2]), 0.02, abs_tol=1e-9)
