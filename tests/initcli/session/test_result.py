"""initcli.session.result: SessionResult.errors against the true poses."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.se2 import Pose2D
from initcli.session.result import SessionResult


def test_errors_all_none_without_poses() -> None:
    trans, rot = SessionResult(False, "distance limit", None).errors()
    assert trans == {"coarse": None, "rectified": None, "fine": None}
    assert rot == trans


def test_errors_per_stage_translation_and_wrapped_rotation() -> None:
    truth = Pose2D(1.0, 1.0, math.radians(179.0))
    result = SessionResult(
        True,
        "converged",
        "L0",
        pose=Pose2D(1.0, 1.5, math.radians(178.0)),
        covariance=np.eye(3) * 0.01,
        coarse_pose=Pose2D(4.0, 5.0, math.radians(-179.0)),
        rectified_pose=Pose2D(1.3, 1.4, math.radians(179.0)),
        truth_pose=truth,
        truth_at_coarse=truth,
    )
    trans, rot = result.errors()
    assert trans == {"coarse": 5.0, "rectified": 0.5, "fine": 0.5}
    assert rot["coarse"] == 2.0  # across +-180 deg, not 358
    assert rot["rectified"] == 0.0
    assert rot["fine"] == 1.0


def test_fine_error_needs_a_covariance() -> None:
    result = SessionResult(
        False, "distance limit", "L0", pose=Pose2D(0, 0, 0), truth_pose=Pose2D(3, 4, 0), covariance=None
    )
    trans, rot = result.errors()
    assert trans["fine"] is None and rot["fine"] is None
    result.covariance = np.eye(3)
    assert result.errors()[0]["fine"] == 5.0
