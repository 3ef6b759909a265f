"""The camera mount from a ROS transform of the optical frame, and back (core/projection.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.depth import window_depth
from initcli.core.geometry.projection import (
    R_BODY_OPTICAL,
    CameraMount,
    mount_from_optical,
    optical_rotation,
    rpy_from_matrix,
    rpy_matrix,
)


@pytest.mark.parametrize(
    "rpy", [(0.0, 0.0, 0.0), (0.1, -0.2, 0.3), (-0.05, 0.4, -2.9), (0.0, math.pi / 2, 0.7)]
)
def test_rpy_round_trip(rpy):
    r = rpy_matrix(*rpy)
    assert np.allclose(rpy_matrix(*rpy_from_matrix(r)), r, atol=1e-12)


def test_level_camera_optical_axes():
    """A level, forward-looking camera: the optical z (forward) is the base x, optical x (right) is
    the base -y, optical y (down) is the base -z (REP 103)."""
    mount = mount_from_optical(R_BODY_OPTICAL, np.array([0.2, 0.0, 1.0]))
    assert (mount.roll, mount.pitch, mount.yaw) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert (mount.x, mount.y, mount.z) == (0.2, 0.0, 1.0)


def test_pitched_camera_round_trip():
    mount = CameraMount(0.1, -0.05, 0.8, 0.02, math.radians(12), math.radians(-7))
    r = optical_rotation(mount)
    assert r[:, 2] @ np.array([0.0, 0.0, 1.0]) < 0  # pitched down: the optical axis points below level
    back = mount_from_optical(r, mount.translation)
    for a, b in zip((back.roll, back.pitch, back.yaw), (mount.roll, mount.pitch, mount.yaw), strict=True):
        assert a == pytest.approx(b, abs=1e-12)


def test_window_depth_mean_of_valid_pixels():
    depth = np.zeros((10, 10), np.float32)
    depth[4:7, 4:7] = 2.0
    depth[5, 5] = 5.0
    assert window_depth(depth, 5.5, 5.5, 1) == pytest.approx((8 * 2.0 + 5.0) / 9)
    assert window_depth(depth, 1.0, 1.0, 1) is None
