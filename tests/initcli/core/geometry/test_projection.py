"""Eq. 1-2 (box centre + depth -> odom) with its inverse, and the camera rotation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.projection import (
    CameraIntrinsics,
    CameraMount,
    bbox_centre,
    box_for_point,
    detections_to_odom,
    odom_to_pixel,
    pixel_to_optical,
    rpy_matrix,
)
from initcli.core.geometry.se2 import Pose2D

CAM = CameraIntrinsics(fx=500.0, fy=500.0, cx=320.0, cy=240.0, width=640, height=480)


def test_eq1_hand_computed() -> None:
    # Eq. 1: x_c = (b_x - p_x) D / f, y_c = (b_y - p_y) D / f, z_c = D
    p = pixel_to_optical(np.array([420.0]), np.array([140.0]), np.array([2.0]), CAM)
    assert np.allclose(p, [[0.4, -0.4, 2.0]])


def test_eq2_hand_computed() -> None:
    # box centre (420, 240), depth 2 -> optical (0.4, 0, 2) -> camera body (2, -0.4, 0)
    # -> base (2.2, -0.4, 1.0) with the camera 0.2 m ahead, 1 m up -> odom with the robot at (1, 2, 90 deg)
    box = np.array([[400.0, 200.0, 440.0, 280.0]])
    mount = CameraMount(x=0.2, z=1.0)
    got = detections_to_odom(box, np.array([2.0]), CAM, mount, Pose2D(1.0, 2.0, math.pi / 2))
    assert np.allclose(got, [[1.4, 4.2, 1.0]])
    # the camera turned left by 90 deg on the robot
    left = CameraMount(x=0.2, z=1.0, yaw=math.pi / 2)
    got = detections_to_odom(box, np.array([2.0]), CAM, left, Pose2D.identity())
    assert np.allclose(got, [[0.6, 2.0, 1.0]])
    # pitched down by 30 deg: the point on the optical axis at depth 2 is 1 m below the camera
    down = CameraMount(z=1.0, pitch=math.radians(30))
    got = detections_to_odom(
        np.array([[310.0, 230.0, 330.0, 250.0]]), np.array([2.0]), CAM, down, Pose2D.identity()
    )
    assert np.allclose(got, [[2 * math.cos(math.radians(30)), 0.0, 0.0]], atol=1e-12)


def test_rpy_matrix_is_a_rotation() -> None:
    r = rpy_matrix(0.3, -0.2, 1.1)
    assert np.allclose(r @ r.T, np.eye(3))
    assert np.linalg.det(r) == pytest.approx(1.0)


@pytest.mark.parametrize("seed", range(5))
def test_inverse_projection_round_trip(seed: int) -> None:
    rng = np.random.default_rng(seed)
    mount = CameraMount(0.15, -0.05, 0.9, rng.normal(0, 0.05), rng.normal(0, 0.1), rng.normal(0, 0.3))
    robot = Pose2D(*rng.uniform(-10, 10, 2), rng.uniform(-math.pi, math.pi))
    # points in front of the camera
    ahead = np.column_stack([rng.uniform(1, 6, 20), rng.uniform(-1, 1, 20), rng.uniform(0.2, 2, 20)])
    pts = np.column_stack([robot.apply(ahead[:, :2]), ahead[:, 2]])
    u, v, d = odom_to_pixel(pts, CAM, mount, robot)
    assert (d > 0).all()
    boxes = np.array([box_for_point(a, b, c, 1.0, 2.0, CAM) for a, b, c in zip(u, v, d, strict=True)])
    assert np.allclose(bbox_centre(boxes), np.column_stack([u, v]))
    back = detections_to_odom(boxes, d, CAM, mount, robot)
    assert np.allclose(back, pts, atol=1e-9)
