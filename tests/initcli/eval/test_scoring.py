"""The paper's failure and averaging rules (§4.3) on hand-made trial records."""

from __future__ import annotations

import math

import pytest

from initcli.baselines.outcome import LocalisationOutcome
from initcli.core.geometry.se2 import Pose2D
from initcli.eval.records import FailureRule, TrialRecord
from initcli.eval.scoring import judge, pose_errors, score, summarise

RULE = FailureRule(max_distance_m=150.0, max_error_m=5.0, wrong_error_m=2.0)


def record(method: str, success: bool, distance: float, error: float | None, **kw) -> TrialRecord:
    return TrialRecord(
        site=kw.pop("site", "a"),
        start=kw.pop("start", 0),
        method=method,
        success=success,
        reason="",
        features=kw.pop("features", 4),
        distance_m=distance,
        error_translation_m=error,
        error_rotation_deg=kw.pop("rot", None if error is None else 10 * error),
        confident_wrong=kw.pop("wrong", False),
        seconds=kw.pop("seconds", 1.0),
        **kw,
    )


def test_failure_rule_distance_error_and_no_result():
    assert judge(True, 40.0, 0.2, RULE)[0] is True
    assert judge(True, 150.5, 0.2, RULE) == (False, "moved more than 150 m", False)
    ok, reason, wrong = judge(True, 40.0, 5.01, RULE)
    assert not ok and "5.01" in reason and wrong
    assert judge(False, 151.0, None, RULE) == (False, "no result", False)
    # exactly at the thresholds still counts as a success
    assert judge(True, 150.0, 5.0, RULE)[0] is True


def test_confident_wrong_counts_claims_far_from_truth_even_when_successful():
    ok, _, wrong = judge(True, 10.0, 3.0, RULE)  # within 5 m (success) but the wrong place
    assert ok and wrong
    ok, _, wrong = judge(True, 10.0, 1.5, RULE)
    assert ok and not wrong


def test_score_measures_errors_against_the_truth_at_the_claim():
    outcome = LocalisationOutcome(
        "amcl", True, "converged", Pose2D(1.0, 2.0, 0.1), Pose2D(1.3, 2.4, -0.1), 12.0, 30.0, 0, 0.5
    )
    r = score(outcome, RULE, site="s", start=3, seed=4, start_pose=(0.0, 0.0, math.pi / 2))
    assert r.error_translation_m == pytest.approx(0.5)
    assert r.error_rotation_deg == pytest.approx(math.degrees(0.2), abs=1e-3)
    assert r.success and not r.confident_wrong
    assert (r.site, r.start, r.method, r.seed) == ("s", 3, "amcl", 4)
    assert r.start_pose == [0.0, 0.0, 90.0]
    nothing = LocalisationOutcome("markers", False, "no marker", None, Pose2D(0, 0, 0), 150.2, 400.0)
    r = score(nothing, RULE, site="s", start=0, seed=1, start_pose=(0.0, 0.0, 0.0))
    assert not r.success and r.error_translation_m is None and r.reason.startswith("no result")
    assert pose_errors(nothing) == (None, None)


def test_rotation_error_wraps_around_pi():
    outcome = LocalisationOutcome(
        "bim", True, "", Pose2D(0, 0, math.pi - 0.01), Pose2D(0, 0, -math.pi + 0.01), 1.0, 1.0
    )
    assert pose_errors(outcome)[1] == pytest.approx(math.degrees(0.02))


def test_averages_are_over_successful_trials_only():
    rows = [
        record("bim", True, 10.0, 0.2, features=4, start=0),
        record("bim", True, 20.0, 0.4, features=6, start=1),
        record("bim", False, 150.0, None, features=9, start=2),
        record("bim", False, 30.0, 7.0, features=9, start=3, wrong=True),
        record("amcl", True, 2.0, 1.0, start=0),
    ]
    by = {s.method: s for s in summarise(rows)}
    bim = by["bim"]
    assert (bim.trials, bim.successes, bim.success_rate) == (4, 2, 50.0)
    assert bim.distance_mean_m == pytest.approx(15.0)
    assert bim.error_translation_mean_m == pytest.approx(0.3)
    assert bim.error_translation_median_m == pytest.approx(0.3)
    assert bim.features_mean == pytest.approx(5.0)
    assert bim.confident_wrong == 1
    assert bim.error_translation_p95_m == pytest.approx(0.39)
    assert by["amcl"].trials == 1 and by["amcl"].success_rate == 100.0


def test_no_success_gives_no_means_and_sweeps_group_apart():
    rows = [
        record("amcl", False, 150.0, None, sweep_key="alpha", sweep_value="0.4"),
        record("amcl", True, 3.0, 0.1, sweep_key="alpha", sweep_value="0.6"),
    ]
    s = summarise(rows)
    assert [x.sweep_value for x in s] == ["0.4", "0.6"]
    assert s[0].distance_mean_m is None and s[0].error_translation_mean_m is None
    assert s[1].error_translation_mean_m == pytest.approx(0.1)


def test_facing_the_wrong_way_is_confident_wrong_too():
    ok, _, wrong = judge(True, 10.0, 0.3, RULE, error_deg=179.0)
    assert ok and wrong  # within the paper's 5 m rule, but turned round
    assert judge(True, 10.0, 0.3, RULE, error_deg=10.0)[2] is False


def test_refused_starts_are_counted_apart_from_failures():
    """A start the simulator refused (a space closed off, known at 0 m) is neither a success nor a
    failure: the success rate is over the accepted starts, the refusals are counted on their own."""
    refused = LocalisationOutcome("bim", False, "cannot leave: ...", None, None, 0.0, 0.0, refused=True)
    r = score(refused, RULE, site="a", start=2, seed=3, start_pose=(0.0, 0.0, 0.0))
    assert r.refused and not r.success and not r.confident_wrong and r.reason.startswith("refused start")
    rows = [
        record("bim", True, 10.0, 0.2, start=0),
        record("bim", False, 150.0, None, start=1),
        r,
        record("bim", False, 0.0, None, start=3, refused=True),
    ]
    (bim,) = summarise(rows)
    assert (bim.trials, bim.refused, bim.successes, bim.success_rate) == (4, 2, 1, 50.0)
    (none_accepted,) = summarise([r])
    assert none_accepted.success_rate == 0.0 and none_accepted.refused == 1
