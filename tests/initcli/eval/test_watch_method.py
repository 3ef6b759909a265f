"""The watch method of ``bim-init eval``: a simulated kidnap (``sim.kidnap``) is found lost and the
robot found again where it is; a run without one raises no alarm; the records score and tabulate
as the issue asks (lost within 15 m, false alarms per km, recoveries right and wrong)."""

from __future__ import annotations

import dataclasses

import pytest

from initcli.config import load_config
from initcli.config.building import prepare_site
from initcli.core.geometry.se2 import Pose2D
from initcli.eval.records import FailureRule
from initcli.eval.results_file import parse_record, record_line
from initcli.eval.watch_table import watch_record, watch_rows
from initcli.watch import sim_trial
from initcli.watch.sim_trial import WatchTrial, watch_trial
from tests.helpers import SAMPLES

START = Pose2D(10.0, 11.0, 0.0)  # block_a's corridor


@pytest.fixture(scope="module")
def block_a(tmp_path_factory):
    config = load_config(SAMPLES / "block_a.site.yaml")
    return config, prepare_site(config, tmp_path_factory.mktemp("site"))


def test_a_simulated_kidnap_is_found_and_the_robot_with_it(block_a, monkeypatch):
    config, site = block_a
    monkeypatch.setattr(sim_trial, "AFTER_KIDNAP_M", 30.0)
    kidnapped = dataclasses.replace(config, sim=dataclasses.replace(config.sim, kidnap=20.0))
    trial = watch_trial(kidnapped, site, 1, START)
    assert trial.kidnap_m is not None and abs(trial.kidnap_m - 20.0) < 1.0
    assert trial.false_alarms == 0 and trial.control_m >= 19.0
    assert trial.lost_after_m is not None and trial.lost_after_m <= 15.0
    assert trial.recovery_error is not None, [e.reason for e in trial.events]
    assert trial.recovered_right
    record = watch_record(trial, FailureRule(), site="block_a", start=0, seed=1, sweep=("", ""))
    assert record.success and not record.wrong_recovery and record.method == "watch"
    assert parse_record(__import__("json").loads(record_line(record)), "results.jsonl:1") == record


def _trial(**kw: object) -> WatchTrial:
    base = {"storey": "L", "start": Pose2D(0, 0, 0), "travel": 100.0, "control_m": 60.0}
    return WatchTrial(**(base | kw))  # type: ignore[arg-type]


def test_the_table_counts_detections_false_alarms_and_recoveries():
    rule = FailureRule()
    trials = [
        _trial(
            kidnap_m=30.0,
            lost_after_m=6.0,
            recovered_after_m=9.0,
            recovery_error=(0.1, 1.0),
            recovered=Pose2D(1, 1, 0),
        ),
        _trial(kidnap_m=30.0, lost_after_m=20.0),  # found too late, never recovered
        _trial(
            kidnap_m=30.0,
            lost_after_m=4.0,
            recovered_after_m=5.0,
            recovery_error=(6.0, 2.0),
            recovered=Pose2D(9, 9, 0),
        ),
        _trial(control_m=1000.0, false_alarms=1),
    ]
    records = [watch_record(t, rule, site="s", start=i, seed=i, sweep=("", "")) for i, t in enumerate(trials)]
    assert [r.success for r in records] == [True, False, False, False]
    assert [r.wrong_recovery for r in records] == [False, False, True, False]
    header, rows = watch_rows(records)
    row = dict(zip(header, rows[0], strict=True))
    assert row["kidnaps"] == "3" and row["lost within 15 m"] == "2/3" and row["median m to lost"] == "5.0"
    assert row["false alarms per km"] == "0.85 (1 in 1.18 km)"
    assert row["recovered within 0.5 m, 5 deg"] == "1/3" and row["wrong recoveries"] == "1"
