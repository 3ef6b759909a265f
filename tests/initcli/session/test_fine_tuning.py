"""How fine tuning settles: keep the carried rectified pose, reseed, give up, or accept the filter."""

from __future__ import annotations

import math

import numpy as np

from bimtools.site.records import Feature
from initcli.config.session import FineTuningSection
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.geometry.se2 import Pose2D
from initcli.core.verify.params import VerificationParams
from initcli.session.fine_tuning import Settlement, matched_pairs
from initcli.session.fine_tuning import settle as settle_with

PARAMS = FineTuningSection()  # the defaults
KEEP_RECTIFIED_MARGIN = PARAMS.keep_rectified_margin
MIN_SCAN_FIT = VerificationParams().min_fine_scan_fit  # the fine pose's own scan-fit rule
HERE = Pose2D(10.0, 5.0, 0.3)
FAR = Pose2D(10.0 + 2 * PARAMS.drifted_distance, 5.0, 0.3)
TURNED = Pose2D(10.0, 5.0, 0.3 + math.radians(2 * PARAMS.drifted_turn))


def settle(estimate: Pose2D, fit: float, carried: Pose2D, carried_fit: float, reseeded: bool) -> Settlement:
    return settle_with(estimate, fit, carried, carried_fit, reseeded, PARAMS, MIN_SCAN_FIT)


def test_a_filter_that_fits_the_scan_is_accepted_even_first_time():
    assert settle(HERE, 0.9, HERE, 0.9, reseeded=False) == "accept"
    # close to the carried pose: the carried pose's better fit does not matter
    assert settle(HERE, 0.7, HERE, 0.99, reseeded=False) == "accept"


def test_a_drifted_filter_gives_way_to_a_carried_pose_that_fits_clearly_better():
    for carried in (FAR, TURNED):
        assert (
            settle(HERE, 0.7, carried, 0.7 + KEEP_RECTIFIED_MARGIN + 0.05, reseeded=False) == "keep rectified"
        )
        # not clearly better: the filter stays
        assert settle(HERE, 0.7, carried, 0.7 + KEEP_RECTIFIED_MARGIN / 2, reseeded=False) == "accept"


def test_a_carried_pose_that_fits_badly_is_not_kept():
    fit = MIN_SCAN_FIT - KEEP_RECTIFIED_MARGIN - 0.1
    assert settle(HERE, fit, FAR, MIN_SCAN_FIT - 0.05, reseeded=False) == "reseed"


def test_a_bad_fit_reseeds_once_then_is_lost():
    assert settle(HERE, MIN_SCAN_FIT - 0.1, HERE, 0.0, reseeded=False) == "reseed"
    assert settle(HERE, MIN_SCAN_FIT - 0.1, HERE, 0.0, reseeded=True) == "lost"


def test_matched_pairs_leave_out_outliers_and_unknown_features():
    features = [ConfirmedFeature(i, "door", float(i), 2.0 * i, 5, 0.0, 1.0) for i in range(3)]
    bim = [
        Feature("d1", "door", 7.0, 8.0, 0.0, 1.0, 1.0, 2.1),
        Feature("d2", "door", 9.0, 4.0, 1.0, 0.0, 1.0, 2.1),
    ]
    odom_xy, bim_xy = matched_pairs(features, ["d2", None, "gone"], bim)
    np.testing.assert_array_equal(odom_xy, [[0.0, 0.0]])
    np.testing.assert_array_equal(bim_xy, [[9.0, 4.0]])
    odom_xy, bim_xy = matched_pairs(features, [None, None, None], bim)
    assert odom_xy.shape == (0, 2) and bim_xy.shape == (0, 2)
