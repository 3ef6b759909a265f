"""The watch method's trials (``--methods watch``, :mod:`initcli.watch.sim_trial`) as records and
as ``table.md``'s "Lost and found" table: per site, the kidnaps found lost within
:data:`DETECT_M` m, the median metres to it, false alarms per km of travel with the localiser
right, the recoveries right, the median metres to them, and the wrong ones."""

from __future__ import annotations

import math
import statistics

from initcli.eval.records import FailureRule, TrialRecord
from initcli.eval.tables import NONE
from initcli.watch.sim_trial import RIGHT_DEG, RIGHT_M, WatchTrial

__all__ = ["DETECT_M", "watch_record", "watch_rows"]

DETECT_M = 15.0  # m: a kidnap found lost within this much travel counts as detected (issue 49's goal)


def watch_record(
    trial: WatchTrial, rule: FailureRule, *, site: str, start: int, seed: int, sweep: tuple[str, str]
) -> TrialRecord:
    """One ``results.jsonl`` row: a success is no false alarm and, with a kidnap, lost within
    DETECT_M m and recovered within RIGHT_M m and RIGHT_DEG degrees of the truth."""
    err = trial.recovery_error
    wrong = err is not None and (err[0] > rule.wrong_error_m or err[1] > rule.wrong_error_deg)
    if trial.kidnap_m is None:
        success, reason = trial.false_alarms == 0, "no kidnap"
    else:
        found = trial.lost_after_m is not None and trial.lost_after_m <= DETECT_M
        success = trial.false_alarms == 0 and found and trial.recovered_right
        lost = "never lost" if trial.lost_after_m is None else f"lost after {trial.lost_after_m:.1f} m"
        back = "not recovered" if err is None else f"recovered {err[0]:.2f} m, {err[1]:.1f} deg off"
        reason = f"kidnapped at {trial.kidnap_m:.1f} m: {lost}, {back}"
    if trial.false_alarms:
        reason += f"; {trial.false_alarms} false alarm(s)"
    start_pose = trial.start
    return TrialRecord(
        site=site,
        start=start,
        method="watch",
        success=success,
        reason=reason,
        features=0,
        distance_m=round(trial.travel, 3),
        error_translation_m=None if err is None else round(err[0], 4),
        error_rotation_deg=None if err is None else round(err[1], 3),
        confident_wrong=wrong,
        seconds=round(trial.seconds, 3),
        localised=trial.recovered is not None,
        seed=seed,
        start_pose=[round(start_pose.x, 3), round(start_pose.y, 3), round(math.degrees(start_pose.yaw), 2)],
        pose=None if trial.recovered is None else [trial.recovered.x, trial.recovered.y, trial.recovered.yaw],
        truth=None if trial.truth is None else [trial.truth.x, trial.truth.y, trial.truth.yaw],
        sweep_key=sweep[0],
        sweep_value=sweep[1],
        kidnap_m=None if trial.kidnap_m is None else round(trial.kidnap_m, 3),
        lost_after_m=None if trial.lost_after_m is None else round(trial.lost_after_m, 3),
        recovered_after_m=None if trial.recovered_after_m is None else round(trial.recovered_after_m, 3),
        control_m=round(trial.control_m, 3),
        false_alarms=trial.false_alarms,
        wrong_recovery=wrong,
    )


def _median(values: list[float]) -> str:
    return f"{statistics.median(values):.1f}" if values else NONE


def watch_rows(records: list[TrialRecord]) -> tuple[list[str], list[list[str]]]:
    """The "Lost and found" table: one row per site (no rows without watch trials)."""
    header = ["site", "trials", "kidnaps", f"lost within {DETECT_M:g} m", "median m to lost"]
    header += ["false alarms per km", f"recovered within {RIGHT_M:g} m, {RIGHT_DEG:g} deg", "median m to it"]
    header += ["wrong recoveries"]
    rows = []
    mine = [r for r in records if r.method == "watch" and not r.refused]
    for site in sorted({r.site for r in mine}):
        trials = [r for r in mine if r.site == site]
        kidnaps = [r for r in trials if r.kidnap_m is not None]
        lost = [r.lost_after_m for r in kidnaps if r.lost_after_m is not None and r.lost_after_m <= DETECT_M]
        right = [
            r
            for r in kidnaps
            if r.error_translation_m is not None
            and r.error_rotation_deg is not None
            and r.error_translation_m <= RIGHT_M
            and r.error_rotation_deg <= RIGHT_DEG
        ]
        km = sum(r.control_m for r in trials) / 1000.0
        alarms = sum(r.false_alarms for r in trials)
        rate = f"{alarms / km:.2f} ({alarms} in {km:.2f} km)" if km > 0 else NONE
        rows.append(
            [
                site,
                str(len(trials)),
                str(len(kidnaps)),
                f"{len(lost)}/{len(kidnaps)}" if kidnaps else NONE,
                _median([x for x in lost if x is not None]),
                rate,
                f"{len(right)}/{len(kidnaps)}" if kidnaps else NONE,
                _median([r.recovered_after_m for r in right if r.recovered_after_m is not None]),
                str(sum(r.wrong_recovery for r in kidnaps)),
            ]
        )
    return header, rows
