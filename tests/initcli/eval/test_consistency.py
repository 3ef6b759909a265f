"""The covariance sent with a pose, judged: the NEES of a claimed pose against the truth under its
own covariance, and the table that counts poses inside the 99 % ellipse and overconfident ones."""

from __future__ import annotations

import math

import numpy as np

from initcli.baselines.outcome import LocalisationOutcome
from initcli.core.geometry.se2 import Pose2D
from initcli.eval.consistency import CHI2_99_3DOF, consistency_rows
from initcli.eval.records import FailureRule
from initcli.eval.scoring import score


def _record(error_m: float, sigma_m: float, start: int = 0):
    cov = np.diag([sigma_m**2, sigma_m**2, math.radians(1.0) ** 2])
    outcome = LocalisationOutcome(
        "bim+pf",
        True,
        "converged",
        Pose2D(error_m, 0.0, 0.0),
        Pose2D(0.0, 0.0, 0.0),
        20.0,
        40.0,
        covariance=cov,
    )
    return score(outcome, FailureRule(), site="s", start=start, seed=start, start_pose=(0.0, 0.0, 0.0))


def test_nees_is_the_error_weighed_by_the_inverse_covariance():
    record = _record(0.2, 0.1)
    assert record.nees is not None and abs(record.nees - 4.0) < 1e-6  # (0.2 / 0.1)^2
    assert record.sigma_m == 0.1


def test_a_pose_without_a_covariance_has_no_nees():
    outcome = LocalisationOutcome("bim", True, "unique", Pose2D(0, 0, 0), Pose2D(0, 0, 0), 10.0, 20.0)
    record = score(outcome, FailureRule(), site="s", start=0, seed=0, start_pose=(0.0, 0.0, 0.0))
    assert record.nees is None and record.sigma_m is None


def test_the_table_counts_the_ellipse_and_the_overconfident():
    records = [_record(0.05, 0.05, 0), _record(0.1, 0.05, 1), _record(0.45, 0.03, 2), _record(0.45, 0.3, 3)]
    assert [r.nees is not None and r.nees <= CHI2_99_3DOF for r in records] == [True, True, False, True]
    header, rows = consistency_rows(records)
    row = dict(zip(header, rows[0], strict=True))
    assert row["poses with a covariance"] == "4"
    assert row["inside the 99 % ellipse"] == "3/4 (75 %)"
    assert row["overconfident (> 0.3 m, sigma < 0.1 m)"] == "1"
