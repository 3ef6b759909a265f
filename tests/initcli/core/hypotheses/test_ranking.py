"""Counting and ranking rules of initcli.core.hypotheses.ranking (outliers vs full matches,
pose-distinctness)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.ranking import (
    confidences,
    drop_dominated,
    one_place,
    pose_groups,
    rank_order,
    verdict_text,
)

X = -1  # outlier


def test_sub_matches_of_a_better_match_are_dropped() -> None:
    assign = np.array(
        [
            [1, 2, 3, 4],  # full match
            [1, 2, X, 4],  # same place, s3 declared false: a sub-match of the full one -> dropped
            [1, 2, 3, X],  # ditto
            [5, X, 7, 8],  # another place with s2 as outlier: no better match agrees -> kept
            [1, X, X, 4],  # two outliers, sub-match of the full match -> dropped
            [5, X, X, 8],  # two outliers, sub-match of [5, X, 7, 8] -> dropped
            [9, X, X, 6],  # two outliers, nothing agrees -> kept
        ]
    )
    n_out = (assign == X).sum(axis=1)
    assert drop_dominated(assign, n_out).tolist() == [True, False, False, True, False, False, True]


def test_matches_differing_only_in_the_outlier_are_both_kept_then_merged_by_pose() -> None:
    # s2 or s3 as the outlier at the same place: neither is a sub-match of the other...
    assign = np.array([[1, X, 3, 4], [1, 2, X, 4]])
    assert drop_dominated(assign, np.array([1, 1])).tolist() == [True, True]
    # ...but they put the robot at the same pose, so they are one hypothesis
    poses = np.array([[10.0, 5.0, 0.1], [10.05, 5.02, 0.11]])
    labels, reps = pose_groups(
        poses, np.zeros(2, int), rank_order(np.array([1, 1]), np.array([0.3, 0.2])), 1.0, 0.2
    )
    assert reps == [1] and labels.tolist() == [0, 0]


def test_fewer_outliers_rank_first_then_cost() -> None:
    order = rank_order(np.array([1, 0, 0, 1]), np.array([0.1, 0.9, 0.5, 0.05]))
    assert order.tolist() == [2, 1, 3, 0]


def test_pose_distinct_counting() -> None:
    poses = np.array(
        [
            [0.0, 0.0, 0.0],
            [0.5, 0.0, 0.05],  # close in position and yaw: same hypothesis
            [0.5, 0.0, math.pi],  # same place, opposite heading: distinct
            [3.0, 0.0, 0.0],  # elsewhere: distinct
            [0.0, 0.0, 0.0],  # same pose on another storey: distinct
        ]
    )
    storey = np.array([0, 0, 0, 0, 1])
    labels, reps = pose_groups(poses, storey, np.arange(5), 1.0, math.radians(15))
    assert reps == [0, 2, 3, 4]
    assert labels.tolist() == [0, 0, 1, 2, 3]


def test_verdict_text() -> None:
    assert verdict_text(0) == "no consistent match"
    assert verdict_text(1) == "unique match"
    assert verdict_text(7) == "7 hypotheses"


def test_confidences() -> None:
    c = confidences(np.array([0.2, 0.2, 1.0]), np.array([0, 1, 0]))
    assert c.sum() == pytest.approx(1.0)
    assert c[0] > c[2] > 0 and c[0] > c[1]
    assert confidences(np.array([0.7]), np.array([1])) == pytest.approx([1.0])


def test_hypotheses_that_put_the_robot_on_one_spot_are_one_place() -> None:
    best = Pose2D(10.0, 2.0, 0.5)
    near = Pose2D(10.6, 2.3, 0.5 + math.radians(10.0))
    assert one_place(["L1", "L1"], [best, near], 1.0, math.radians(15.0))
    assert not one_place(["L1"], [best], 1.0, math.radians(15.0))  # one hypothesis: nothing to merge
    assert not one_place(["L1", "L2"], [best, near], 1.0, math.radians(15.0))  # another storey
    assert not one_place(["L1", "L1"], [best, Pose2D(11.2, 2.0, 0.5)], 1.0, math.radians(15.0))  # 1.2 m
    turned = Pose2D(10.0, 2.0, 0.5 + math.radians(20.0))
    assert not one_place(["L1", "L1", "L1"], [best, near, turned], 1.0, math.radians(15.0))  # 20 degrees


def test_one_hypothesis_per_place_is_kept_best_first() -> None:
    from initcli.core.hypotheses.ranking import distinct_places

    poses = [
        Pose2D(10.0, 5.0, 0.0),
        Pose2D(25.0, 5.0, 0.0),  # another place
        Pose2D(10.4, 5.3, math.radians(5.0)),  # the first place again (split by rule 3's fit)
        Pose2D(10.0, 5.0, math.radians(90.0)),  # the first place turned: another pose
        Pose2D(10.0, 5.0, 0.0),  # the same pose on another storey
    ]
    storeys = ["L1", "L1", "L1", "L1", "L2"]
    assert distinct_places(storeys, poses, 1.0, math.radians(15.0)) == [0, 1, 3, 4]
    assert distinct_places([], [], 1.0, 0.3) == []
