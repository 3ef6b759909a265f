"""Pose2D / SE(2) helpers: compose, inverse, apply, angle wrapping."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.se2 import Pose2D, transform_poses, wrap_angle


def test_pose_compose_inverse_and_apply() -> None:
    a = Pose2D(1.0, 2.0, 0.7)
    b = Pose2D(-3.0, 0.5, -2.0)
    ident = a * a.inverse()
    assert ident.x == pytest.approx(0.0, abs=1e-12) and ident.y == pytest.approx(0.0, abs=1e-12)
    assert ident.yaw == pytest.approx(0.0, abs=1e-12)
    p = np.array([[0.3, -1.2], [4.0, 5.0]])
    assert np.allclose((a * b).apply(p), a.apply(b.apply(p)))
    assert np.allclose(a.apply_inverse(a.apply(p)), p)
    assert np.allclose(a.matrix() @ b.matrix(), (a * b).matrix())
    assert Pose2D.from_matrix((a * b).matrix()).yaw == pytest.approx((a * b).yaw)
    poses = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, math.pi / 2]])
    moved = transform_poses(Pose2D(0.0, 0.0, math.pi / 2), poses)
    assert np.allclose(moved, [[0.0, 1.0, math.pi / 2], [-1.0, 0.0, -math.pi]])


def test_wrap_angle() -> None:
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert np.allclose(wrap_angle(np.array([0.0, 2 * math.pi, -3 * math.pi / 2])), [0.0, 0.0, math.pi / 2])


def test_wrap_angle_of_a_scalar_is_the_arrays_arithmetic() -> None:
    """Scalars take a path without numpy; it must give the array path's float64 result exactly."""
    rng = np.random.default_rng(3)
    angles = np.concatenate([rng.uniform(-50.0, 50.0, 500), [math.pi, -math.pi, 0.0, 2 * math.pi, 1e-17]])
    wrapped = wrap_angle(angles)
    assert [wrap_angle(float(a)) for a in angles] == wrapped.tolist()
    assert all(-math.pi <= w < math.pi for w in wrapped)
    assert isinstance(wrap_angle(np.float64(4.0)), float) and isinstance(wrap_angle(7), float)


def test_transform_poses_is_compose_for_each_pose_bit_for_bit() -> None:
    """The array form gives exactly the float64 results of ``transform * pose`` (the verification's
    predicted views depend on it)."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        transform = Pose2D(*rng.uniform(-30.0, 30.0, 2), float(rng.uniform(-4.0, 4.0)))
        poses = np.column_stack([rng.uniform(-50.0, 50.0, (100, 2)), rng.uniform(-4.0, 4.0, 100)])
        expected = np.array([(transform * Pose2D(*p)).as_tuple() for p in poses])
        assert np.array_equal(transform_poses(transform, poses), expected)
