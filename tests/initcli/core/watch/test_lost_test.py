"""Page's CUSUM over travel: a right pose's evidence (under the allowance) never accumulates, a
robot standing still adds nothing however many scans it takes, a wrong pose passes the threshold
after the distance the evidence says, and the change is placed where the evidence began."""

from __future__ import annotations

import numpy as np

from initcli.core.watch.lost_test import CusumTest, wrongness
from initcli.core.watch.params import WatchParams

PARAMS = WatchParams()


def _run(test: CusumTest, travel: np.ndarray, evidence: np.ndarray) -> float | None:
    for d, w in zip(travel, evidence, strict=True):
        if test.update(float(d), float(w)):
            return float(d)
    return None


def test_a_right_pose_never_accumulates():
    rng = np.random.default_rng(0)
    travel = np.arange(0.0, 500.0, 0.25)
    evidence = rng.uniform(0.0, PARAMS.allowance, len(travel))
    test = CusumTest(PARAMS)
    assert _run(test, travel, evidence) is None
    assert test.statistic == 0.0


def test_standing_still_adds_nothing():
    test = CusumTest(PARAMS)
    assert _run(test, np.full(10_000, 3.0), np.ones(10_000)) is None
    assert test.statistic == 0.0


def test_a_wrong_pose_is_suspect_after_the_distance_its_evidence_says():
    travel = np.arange(0.0, 40.0, 0.25)
    evidence = np.where(travel >= 10.0, 0.3, 0.0)  # the pose goes wrong at 10 m
    test = CusumTest(PARAMS)
    at = _run(test, travel, evidence)
    expected = 10.0 + PARAMS.threshold / (0.3 - PARAMS.allowance)
    assert at is not None and abs(at - expected) <= 0.5
    assert abs(test.since - 10.0) <= 0.25


def test_one_bad_scan_never_decides():
    travel = np.arange(0.0, 20.0, 0.25)
    evidence = np.zeros(len(travel))
    evidence[40] = 1.0  # everything wrong, once
    assert _run(CusumTest(PARAMS), travel, evidence) is None


def test_evidence_grows_with_beams_through_walls_a_poor_fit_and_places_off_the_map():
    right = wrongness(0.9, 0.02, 0.0, PARAMS)
    assert right < PARAMS.allowance
    assert wrongness(0.2, 0.3, 0.0, PARAMS) > wrongness(0.2, 0.0, 0.0, PARAMS) > right
    assert wrongness(0.5, 0.0, 1.0, PARAMS) > PARAMS.allowance
    assert wrongness(0.95, 0.3, 0.0, PARAMS) < PARAMS.allowance  # glass: beams through a wall that fits
