"""Scoring trials and summarising them (paper §4.3): pure functions on records."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from initcli.baselines.outcome import LocalisationOutcome
from initcli.core.geometry.se2 import wrap_angle
from initcli.eval.records import FailureRule, MethodSummary, TrialRecord

__all__ = ["judge", "pose_errors", "score", "summarise"]


def pose_errors(outcome: LocalisationOutcome) -> tuple[float | None, float | None]:
    """(translation m, rotation deg) of the claimed pose against the truth at the same instant."""
    if outcome.pose is None or outcome.truth is None:
        return None, None
    p, t = outcome.pose, outcome.truth
    return math.hypot(p.x - t.x, p.y - t.y), math.degrees(abs(float(wrap_angle(p.yaw - t.yaw))))


def judge(
    localised: bool,
    distance_m: float,
    error_m: float | None,
    rule: FailureRule,
    error_deg: float | None = None,
) -> tuple[bool, str, bool]:
    """(success, reason, confident_wrong) under the paper's failure rule."""
    wrong = localised and (
        (error_m is not None and error_m > rule.wrong_error_m)
        or (error_deg is not None and error_deg > rule.wrong_error_deg)
    )
    if not localised:
        return False, "no result", False
    if distance_m > rule.max_distance_m:
        return False, f"moved more than {rule.max_distance_m:g} m", wrong
    if error_m is None:
        return False, "no ground truth to score the result", wrong
    if error_m > rule.max_error_m:
        return False, f"error {error_m:.2f} m > {rule.max_error_m:g} m", wrong
    return True, "localised", wrong


def score(
    outcome: LocalisationOutcome,
    rule: FailureRule,
    *,
    site: str,
    start: int,
    seed: int,
    start_pose: tuple[float, float, float],
    sweep: tuple[str, str] = ("", ""),
) -> TrialRecord:
    """One ``results.jsonl`` row from what a method reported."""
    trans, rot = pose_errors(outcome)
    nees, sigma = _consistency(outcome)
    success, verdict, wrong = judge(outcome.localised, outcome.distance_m, trans, rule, rot)
    reason = f"{verdict}: {outcome.reason}" if outcome.localised else f"no result: {outcome.reason}"
    if outcome.refused:
        reason = f"refused start: {outcome.reason}"
    return TrialRecord(
        site=site,
        start=start,
        method=outcome.method,
        success=success,
        reason=reason,
        features=int(outcome.features),
        distance_m=round(float(outcome.distance_m), 3),
        error_translation_m=None if trans is None else round(trans, 4),
        error_rotation_deg=None if rot is None else round(rot, 3),
        confident_wrong=wrong,
        seconds=round(float(outcome.wall_seconds), 3),
        localised=outcome.localised,
        seed=seed,
        start_pose=[round(start_pose[0], 3), round(start_pose[1], 3), round(math.degrees(start_pose[2]), 2)],
        pose=None if outcome.pose is None else _pose_list(outcome.pose.as_tuple()),
        truth=None if outcome.truth is None else _pose_list(outcome.truth.as_tuple()),
        sweep_key=sweep[0],
        sweep_value=sweep[1],
        refused=outcome.refused,
        nees=nees,
        sigma_m=sigma,
    )


def _consistency(outcome: LocalisationOutcome) -> tuple[float | None, float | None]:
    """NEES of the claimed pose against the truth under its own covariance (x, y, yaw; 3 degrees of
    freedom), and the covariance's largest position sigma; None without a covariance."""
    cov = outcome.covariance
    if cov is None or outcome.pose is None or outcome.truth is None or not outcome.localised:
        return None, None
    p, t = outcome.pose, outcome.truth
    error = np.array([p.x - t.x, p.y - t.y, math.remainder(p.yaw - t.yaw, math.tau)])
    c = np.asarray(cov, dtype=float)
    try:
        nees = float(error @ np.linalg.solve(c, error))
    except np.linalg.LinAlgError:
        nees = math.inf
    sigma = float(np.sqrt(max(c[0, 0], c[1, 1], 0.0)))
    return (round(nees, 3) if math.isfinite(nees) else 1e9), round(sigma, 4)


def _pose_list(pose: tuple[float, float, float]) -> list[float]:
    return [round(pose[0], 4), round(pose[1], 4), round(math.degrees(pose[2]), 3)]


def _stats(values: list[float]) -> tuple[float | None, float | None, float | None]:
    if not values:
        return None, None, None
    a = np.asarray(values, dtype=float)
    return float(a.mean()), float(np.median(a)), float(np.percentile(a, 95))


def summarise(records: Iterable[TrialRecord]) -> list[MethodSummary]:
    """One summary per (site, method, sweep value), in first-seen order.

    The paper's averaging rule: distance, features and errors over successful trials only.
    """
    groups: dict[tuple[str, str, str, str], list[TrialRecord]] = {}
    for r in records:
        groups.setdefault((r.site, r.method, r.sweep_key, r.sweep_value), []).append(r)
    out = []
    for (site, method, sweep_key, sweep_value), rows in groups.items():
        ok = [r for r in rows if r.success]
        accepted = [r for r in rows if not r.refused]
        dist = _stats([r.distance_m for r in ok])
        trans = _stats([r.error_translation_m for r in ok if r.error_translation_m is not None])
        rot = _stats([r.error_rotation_deg for r in ok if r.error_rotation_deg is not None])
        out.append(
            MethodSummary(
                site=site,
                method=method,
                trials=len(rows),
                successes=len(ok),
                success_rate=100.0 * len(ok) / len(accepted) if accepted else 0.0,
                confident_wrong=sum(r.confident_wrong for r in rows),
                features_mean=float(np.mean([r.features for r in ok])) if ok else None,
                distance_mean_m=dist[0],
                distance_median_m=dist[1],
                distance_p95_m=dist[2],
                error_translation_mean_m=trans[0],
                error_translation_median_m=trans[1],
                error_translation_p95_m=trans[2],
                error_rotation_mean_deg=rot[0],
                error_rotation_median_deg=rot[1],
                error_rotation_p95_deg=rot[2],
                seconds_mean=float(np.mean([r.seconds for r in rows])),
                sweep_key=sweep_key,
                sweep_value=sweep_value,
                refused=len(rows) - len(accepted),
            )
        )
    return out
