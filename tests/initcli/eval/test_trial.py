"""initcli.eval.trial: the bim and bim+pf outcomes of one session, and the trial seed."""

from __future__ import annotations

from initcli.core.geometry.se2 import Pose2D
from initcli.eval.trial import session_outcomes, trial_seed
from initcli.session.result import CANNOT_LEAVE, SHUT_IN, CoarseClaim, SessionResult


def _result(**kw: object) -> SessionResult:
    base = dict(
        success=False,
        reason="distance limit",
        storey="L0",
        features_detected=7,
        distance_total_m=40.0,
        duration_s=100.0,
        wall_seconds=9.0,
        truth_pose=Pose2D(9, 9, 0),
        truth_at_coarse=Pose2D(2, 2, 0),
    )
    base.update(kw)
    return SessionResult(**base)  # type: ignore[arg-type]


def test_no_unique_match_neither_method_localised() -> None:
    out = session_outcomes(_result())
    bim, pf = out["bim"], out["bim+pf"]
    assert (bim.method, pf.method) == ("bim", "bim+pf")
    assert not bim.localised and not pf.localised
    assert bim.pose is None and pf.pose is None
    assert bim.reason == "distance limit" and bim.distance_m == 40.0 and bim.wall_seconds == 9.0
    assert bim.truth == Pose2D(9, 9, 0)


def test_unique_match_bim_is_rectified_pose_at_the_match() -> None:
    result = _result(
        coarse_pose=Pose2D(2.5, 2, 0),
        rectified_pose=Pose2D(2.1, 2, 0),
        distance_coarse_m=12.0,
        wall_seconds_coarse=3.0,
        first_claim=CoarseClaim(Pose2D(2.1, 2, 0), Pose2D(2, 2, 0), 12.0, 3.0),
    )
    bim = session_outcomes(result)["bim"]
    assert bim.localised and bim.reason == "unique match"
    assert bim.pose == Pose2D(2.1, 2, 0) and bim.truth == Pose2D(2, 2, 0)
    assert bim.distance_m == 12.0 and bim.wall_seconds == 3.0 and bim.features == 7


def test_bim_ends_at_the_first_claim_when_a_failed_fine_stage_led_to_a_second() -> None:
    """The coarse fields describe the last claim; the coarse-only method ends at the first."""
    result = _result(
        success=True,
        pose=Pose2D(30.0, 2, 0),
        coarse_pose=Pose2D(29.5, 2, 0),
        rectified_pose=Pose2D(29.6, 2, 0),
        distance_coarse_m=40.0,
        wall_seconds_coarse=8.0,
        first_claim=CoarseClaim(Pose2D(2.1, 2, 0), Pose2D(2, 2, 0), 12.0, 3.0),
    )
    bim, pf = session_outcomes(result)["bim"], session_outcomes(result)["bim+pf"]
    assert bim.pose == Pose2D(2.1, 2, 0) and bim.distance_m == 12.0 and bim.wall_seconds == 3.0
    assert pf.pose == Pose2D(30.0, 2, 0) and pf.distance_m == 40.0


def test_a_coarse_pose_without_a_claim_record_is_not_a_claim() -> None:
    result = _result(coarse_pose=Pose2D(2.5, 2, 0), rectified_pose=Pose2D(2.1, 2, 0), distance_coarse_m=None)
    assert not session_outcomes(result)["bim"].localised


def test_bim_pf_claims_the_final_pose_only_on_success() -> None:
    ok = session_outcomes(_result(success=True, reason="converged", pose=Pose2D(8, 9, 0)))["bim+pf"]
    assert ok.localised and ok.pose == Pose2D(8, 9, 0) and ok.distance_m == 40.0
    failed = session_outcomes(_result(success=False, pose=Pose2D(8, 9, 0)))["bim+pf"]
    assert not failed.localised and failed.pose is None
    no_pose = session_outcomes(_result(success=True, pose=None))["bim+pf"]
    assert not no_pose.localised


def test_trial_seed_is_distinct_per_start() -> None:
    assert trial_seed(100, 3) == 103
    assert len({trial_seed(7, s) for s in range(10)}) == 10


def test_a_start_refused_at_0_m_is_a_refused_outcome_a_shut_in_one_a_failure() -> None:
    refused = session_outcomes(_result(reason=CANNOT_LEAVE, distance_total_m=0.0))
    assert refused["bim"].refused and refused["bim+pf"].refused
    shut = session_outcomes(_result(reason=SHUT_IN, distance_total_m=17.0))
    assert not shut["bim"].refused and not shut["bim+pf"].localised  # the robot tried: a failure
