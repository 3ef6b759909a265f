"""Pose per hypothesis: trilateration (Eq. 10), heading (Eq. 11-13) and the rigid (Kabsch) alternative."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.pose import (
    estimate_pose,
    heading_from_feature,
    paper_pose,
    rigid_align,
    rigid_align_batch,
    rigid_pose,
    trilaterate,
    trilateration_residuals,
)


def test_eq10_exact_distances() -> None:
    anchors = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 3.0]])
    d = np.array([math.sqrt(2), math.sqrt(10), math.sqrt(5)])  # robot at (1, 1)
    assert np.allclose(trilaterate(anchors, d), [1.0, 1.0], atol=1e-9)
    assert np.allclose(trilateration_residuals(np.array([1.0, 1.0]), anchors, d), 0.0, atol=1e-12)


def test_eq10_inconsistent_distances_hand_computed() -> None:
    # Equilateral anchors around the origin (circumradius R = 2) and the same distance 2.2 to each:
    # no point fits; by symmetry the least-squares solution of Eq. 10 is the centre (d^2 < 2 R^2).
    angles = np.radians([90.0, 210.0, 330.0])
    anchors = 2.0 * np.column_stack([np.cos(angles), np.sin(angles)])
    got = trilaterate(anchors, np.full(3, 2.2))
    assert np.allclose(got, [0.0, 0.0], atol=1e-6)


def test_eq10_collinear_anchors_take_the_robots_side() -> None:
    # Doors along one wall: Eq. 10 has two mirror minima; the odom geometry says which side.
    anchors = np.array([[0.0, 0.0], [3.0, 0.0], [6.0, 0.0]])
    robot = np.array([2.0, 1.0])
    d = np.hypot(*(anchors - robot).T)
    assert np.allclose(trilaterate(anchors, d, anchors, robot), robot, atol=1e-9)
    mirror_odom = anchors * [1, -1]
    assert np.allclose(trilaterate(anchors, d, mirror_odom, robot * [1, -1]), [2.0, -1.0], atol=1e-9)


def test_eq13_hand_computed() -> None:
    # Robot at the origin, the feature 2 m straight ahead in the robot frame, at (0, 2) in BIM: yaw 90 deg.
    assert heading_from_feature(np.zeros(2), np.array([0.0, 2.0]), np.array([2.0, 0.0])) == pytest.approx(
        math.pi / 2
    )
    # Feature at (1, 1) in the robot frame, robot at (5, 5) facing 30 deg: o_b = R(30) (1, 1) + (5, 5).
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    o_b = np.array([5 + c - s, 5 + s + c])
    assert heading_from_feature(np.array([5.0, 5.0]), o_b, np.array([1.0, 1.0])) == pytest.approx(
        math.radians(30)
    )
    # Eq. 12 as a linear system gives the same cos/sin
    a = np.array([[1.0, -1.0], [1.0, 1.0]])
    cos_sin = np.linalg.solve(a, o_b - 5.0)
    assert math.atan2(cos_sin[1], cos_sin[0]) == pytest.approx(math.radians(30))


@pytest.mark.parametrize("seed", range(5))
def test_rigid_align_recovers_transform(seed: int) -> None:
    rng = np.random.default_rng(seed)
    t = Pose2D(*rng.uniform(-20, 20, 2), rng.uniform(-math.pi, math.pi))
    src = rng.uniform(-10, 10, (6, 2))
    got = rigid_align(src, t.apply(src))
    assert got.x == pytest.approx(t.x) and got.y == pytest.approx(t.y)
    assert got.yaw_error(t) < 1e-12
    # a wrong point with zero weight does not disturb the batched version
    dst = t.apply(src)
    dst[2] += [5.0, -3.0]
    w = np.ones((1, 6))
    w[0, 2] = 0.0
    yaw, tr = rigid_align_batch(src[None], dst[None], w)
    assert tr[0] == pytest.approx([t.x, t.y]) and yaw[0] == pytest.approx(t.yaw)


def test_paper_and_rigid_agree_without_noise() -> None:
    rng = np.random.default_rng(11)
    to_bim = Pose2D(12.0, -4.0, 2.1)
    odom_feats = rng.uniform(-8, 8, (5, 2))
    robot_odom = Pose2D(1.0, 0.5, 0.4)
    bim_feats = to_bim.apply(odom_feats)
    expected = to_bim * robot_odom
    for method in ("paper", "rigid"):
        got = estimate_pose(method, bim_feats, odom_feats, robot_odom)
        assert got.distance_to(expected) < 1e-6
        assert got.yaw_error(expected) < 1e-6
    assert (
        paper_pose(bim_feats, odom_feats, robot_odom).distance_to(
            rigid_pose(bim_feats, odom_feats, robot_odom)
        )
        < 1e-6
    )
    with pytest.raises(ValueError):
        estimate_pose("magic", bim_feats, odom_feats, robot_odom)
