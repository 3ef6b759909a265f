"""Algorithm 1 over a mixed sequence (camera features and lidar landmarks): the landmarks' own Eq. 7
threshold and drift allowance, their weight toward min_inliers and their own outlier budget."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from initcli.core.hypotheses.matching import OUTLIER, BimIndex, LandmarkMatching, Matcher, MatchParams

LM = LandmarkMatching(
    classes=frozenset({"ConcaveCorner", "ConvexCorner"}), alpha=0.15, drift=0.0, weight=1.0, outlier_share=0.0
)
PARAMS = MatchParams(
    alpha=0.8, beta=math.radians(15), max_outliers=1, min_inliers=3, revisits=False, landmarks=LM
)


def corners(rng: np.random.Generator, n: int) -> tuple[np.ndarray, list[str]]:
    xy = rng.uniform(0, 40, size=(n, 2))
    cls = list(rng.choice(["ConcaveCorner", "ConvexCorner"], size=n))
    return xy, cls


def matches(b_xy, b_cls, s_xy, s_cls, params, travel=None) -> set[tuple[int, ...]]:
    matcher = Matcher(BimIndex(np.asarray(b_xy), b_cls), params)
    state = matcher.match(np.asarray(s_xy), s_cls, travel)
    return {tuple(int(a) for a in row) for row in state.assign[state.matches(params)]}


def test_without_landmark_classes_the_matcher_is_unchanged() -> None:
    rng = np.random.default_rng(1)
    b_xy = rng.uniform(0, 30, size=(40, 2))
    b_cls = list(rng.choice(["door", "lift"], size=40, p=[0.8, 0.2]))
    walk = [3, 7, 11, 19]
    s_xy = b_xy[walk] + rng.normal(0, 0.1, (4, 2)) + 100.0
    s_cls = [b_cls[i] for i in walk]
    plain = replace(PARAMS, landmarks=None)
    assert matches(b_xy, b_cls, s_xy, s_cls, PARAMS) == matches(b_xy, b_cls, s_xy, s_cls, plain)
    assert tuple(walk) in matches(b_xy, b_cls, s_xy, s_cls, PARAMS)


def test_landmark_alpha_is_tighter_and_grows_with_travel() -> None:
    rng = np.random.default_rng(2)
    b_xy, b_cls = corners(rng, 30)
    walk = [0, 5, 9, 14]
    s_xy = b_xy[walk].copy()
    s_xy[3] += [0.4, 0.0]  # 0.4 m off: within the camera's alpha, beyond the landmarks' 0.15 m
    s_cls = [b_cls[i] for i in walk]
    assert tuple(walk) not in matches(b_xy, b_cls, s_xy, s_cls, PARAMS)
    assert tuple(walk) in matches(b_xy, b_cls, s_xy, s_cls, replace(PARAMS, landmarks=None))
    # confirmed 30 m of travel after the others: a 2 % drift allowance covers 0.4 m
    drifting = replace(PARAMS, landmarks=replace(LM, drift=0.02))
    assert tuple(walk) in matches(b_xy, b_cls, s_xy, s_cls, drifting, travel=[0.0, 0.0, 0.0, 30.0])
    assert tuple(walk) not in matches(b_xy, b_cls, s_xy, s_cls, drifting, travel=[0.0, 0.0, 0.0, 0.0])


def test_landmarks_need_more_members_when_they_weigh_less() -> None:
    rng = np.random.default_rng(3)
    b_xy, b_cls = corners(rng, 30)
    walk = [1, 4, 8, 12, 17, 22]
    s_xy, s_cls = b_xy[walk] + 50.0, [b_cls[i] for i in walk]
    half = replace(PARAMS, landmarks=replace(LM, weight=0.5))
    assert tuple(walk[:5]) not in matches(b_xy, b_cls, s_xy[:5], s_cls[:5], half)  # 5 x 0.5 < 3
    assert tuple(walk) in matches(b_xy, b_cls, s_xy, s_cls, half)  # 6 x 0.5 = 3


def test_clutter_landmarks_use_their_own_outlier_budget() -> None:
    rng = np.random.default_rng(4)
    b_xy, b_cls = corners(rng, 30)
    walk = [2, 6, 10, 15, 20]
    s_xy = b_xy[walk].copy()
    s_cls = [b_cls[i] for i in walk]
    # two landmarks of geometry the BIM lacks (material stacks) inside the sequence
    s_xy = np.insert(s_xy, [0, 3, 4], [[80.0, 80.0], [-30.0, -30.0], [-35.0, 70.0]], axis=0)
    s_cls[0:0] = ["ConcaveCorner"]
    s_cls[4:4] = ["ConvexCorner"]
    s_cls[6:6] = ["ConcaveCorner"]
    expected = (OUTLIER, 2, 6, 10, OUTLIER, 15, OUTLIER, 20)
    no_camera_outliers = replace(PARAMS, max_outliers=0)
    assert expected not in matches(b_xy, b_cls, s_xy, s_cls, no_camera_outliers)
    budget = replace(no_camera_outliers, landmarks=replace(LM, outlier_share=0.5))
    matcher = Matcher(BimIndex(b_xy, b_cls), budget)
    state = matcher.match(s_xy, s_cls)
    rows = state.matches(budget)
    found = {tuple(int(a) for a in state.assign[r]): r for r in rows}
    assert expected in found
    assert state.n_out[found[expected]] == 0  # the camera's budget untouched
    assert LM.budget(3) == 0 and replace(LM, outlier_share=0.34).budget(3) == 1
    assert replace(LM, outlier_share=0.34).budget(6) == 2
    # beyond the budget (3 of 7 with a share of 0.34: 2) the pattern is no match
    tight = replace(no_camera_outliers, landmarks=replace(LM, outlier_share=0.34))
    assert expected not in matches(b_xy, b_cls, s_xy, s_cls, tight)


def test_a_row_skips_a_clutter_landmark_after_its_first_inlier() -> None:
    """The stack's corner seen right after the first matched corner, and after the second: a row of
    one or two inliers declares it an outlier as a row of none or of three does (the rule once kept
    such rows from it, and the true place died wherever clutter followed its first corner)."""
    rng = np.random.default_rng(5)
    b_xy, b_cls = corners(rng, 30)
    walk = [3, 8, 13, 18]
    s_xy = b_xy[walk] + 20.0
    s_cls = [b_cls[i] for i in walk]
    s_xy = np.insert(s_xy, [1, 2], [[95.0, -40.0], [-50.0, 95.0]], axis=0)
    s_cls[1:1] = ["ConvexCorner"]
    s_cls[3:3] = ["ConcaveCorner"]
    expected = (3, OUTLIER, 8, OUTLIER, 13, 18)
    params = replace(PARAMS, max_outliers=0, landmarks=replace(LM, outlier_share=0.5))
    assert expected in matches(b_xy, b_cls, s_xy, s_cls, params)


def test_with_camera_features_landmarks_join_once_two_doors_fix_the_pose() -> None:
    """``anchored`` (a sequence with camera features): a landmark seen before the second door is an
    outlier in every match, one seen after it joins as an inlier, and none starts a candidate."""
    rng = np.random.default_rng(6)
    c_xy, c_cls = corners(rng, 20)
    d_xy = rng.uniform(0, 40, size=(6, 2))
    b_xy, b_cls = np.vstack([c_xy, d_xy]), [*c_cls, *["door"] * 6]
    walk = [2, 20, 5, 21, 9, 22]  # a corner, a door, a corner, a door, a corner, a door
    s_xy, s_cls = b_xy[walk] + 10.0, [b_cls[i] for i in walk]
    anchored = replace(PARAMS, landmarks=replace(LM, outlier_share=1.0, anchored=True))
    found = matches(b_xy, b_cls, s_xy, s_cls, anchored)
    assert (OUTLIER, 20, OUTLIER, 21, 9, 22) in found
    assert all(row[0] == OUTLIER and row[2] == OUTLIER for row in found)
    free = replace(anchored, landmarks=replace(LM, outlier_share=1.0))
    assert tuple(walk) in matches(b_xy, b_cls, s_xy, s_cls, free)
