"""Feature-pattern geometry: Eq. 5 (pair distance), Eq. 8 (signed rotation) and the wrapped difference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.hypotheses.pattern import angle_difference, pair_distance, rotation_angle


def test_pair_distance_is_eq5_over_leading_dimensions() -> None:
    assert pair_distance([0.0, 0.0], [3.0, 4.0]) == pytest.approx(5.0)
    a = np.zeros((2, 3, 2))
    b = np.broadcast_to([6.0, 8.0], (2, 3, 2))
    assert pair_distance(a, b).shape == (2, 3) and np.allclose(pair_distance(a, b), 10.0)


def test_rotation_angle_is_signed_and_scale_free() -> None:
    u = np.array([1.0, 1.0])
    assert rotation_angle(u, u + [1.0, 0.0], u + [0.0, 5.0]) == pytest.approx(
        math.pi / 2
    )  # counter-clockwise
    assert rotation_angle(u, u + [1.0, 0.0], u + [0.0, -0.1]) == pytest.approx(-math.pi / 2)
    assert rotation_angle(u, u + [2.0, 0.0], u + [-3.0, 0.0]) == pytest.approx(math.pi)  # (-pi, pi]
    # invariant under rotating and translating the three points together
    rng = np.random.default_rng(0)
    pts = rng.uniform(-5, 5, (3, 2))
    c, s = math.cos(0.7), math.sin(0.7)
    moved = pts @ np.array([[c, s], [-s, c]]) + [10.0, -4.0]
    assert rotation_angle(*moved) == pytest.approx(rotation_angle(*pts))


def test_angle_difference_wraps_to_zero_pi() -> None:
    assert angle_difference(math.radians(179), math.radians(-179)) == pytest.approx(math.radians(2))
    assert angle_difference(0.0, math.pi) == pytest.approx(math.pi)
    assert angle_difference(0.25, 0.25 + 4 * math.pi) == pytest.approx(0.0, abs=1e-12)
    d = angle_difference(np.array([0.1, -3.0]), np.array([-0.1, 3.0]))
    assert np.allclose(d, [0.2, 2 * math.pi - 6.0])
