"""The one-tag pose (§4.3): the tag's corner geometry, and the robot pose from its 4 corner pixels."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry import Pose2D
from initcli.core.marker_pose import robot_pose_from_marker, tag_object_points, tag_rotation
from initcli.core.projection import CameraIntrinsics, CameraMount, odom_to_optical
from initcli.sim.markers import Marker

CAMERA = CameraIntrinsics(320.0, 320.0, 320.0, 240.0, 640, 480)
MOUNT = CameraMount(0.2, 0.0, 1.0)


def test_tag_rotation_is_a_rotation_facing_along_the_normal() -> None:
    for yaw in (0.0, 0.4, -2.0, math.pi):
        normal = (math.cos(yaw), math.sin(yaw))
        r = tag_rotation(normal)
        assert np.allclose(r.T @ r, np.eye(3)) and np.linalg.det(r) == pytest.approx(1.0)
        assert np.allclose(r[:, 2], [*normal, 0.0])  # z out of the wall
        assert np.allclose(r[:, 1], [0.0, 0.0, 1.0])  # y up
        assert np.allclose(np.cross(r[:, 2], r[:, 0]), r[:, 1])  # x to the viewer's right


def test_object_points_are_the_ippe_square_corners() -> None:
    pts = tag_object_points(0.2)
    assert pts.tolist() == [[-0.1, 0.1, 0.0], [0.1, 0.1, 0.0], [0.1, -0.1, 0.0], [-0.1, -0.1, 0.0]]


def pixels(marker: Marker, truth: Pose2D) -> np.ndarray:
    """The tag corners seen by a pinhole camera at ``truth`` (Eq. 2 forward), noise-free."""
    optical = odom_to_optical(marker.corners(), MOUNT, truth)
    u = CAMERA.fx * optical[:, 0] / optical[:, 2] + CAMERA.cx
    v = CAMERA.fy * optical[:, 1] / optical[:, 2] + CAMERA.cy
    return np.column_stack([u, v])


@pytest.mark.parametrize(("distance", "view_deg"), [(1.5, 20.0), (2.5, -35.0), (3.0, 45.0)])
def test_pose_from_exact_corners_is_the_truth(distance: float, view_deg: float) -> None:
    marker = Marker(3, 4.0, -2.0, 1.1, (0.0, 1.0), math.pi / 2)
    a = marker.yaw + math.radians(view_deg)
    cam = np.array([marker.x, marker.y]) + distance * np.array([math.cos(a), math.sin(a)])
    yaw = a + math.pi + math.radians(5.0)  # the tag a little off the image centre
    truth = Pose2D(cam[0] - MOUNT.x * math.cos(yaw), cam[1] - MOUNT.x * math.sin(yaw), yaw)
    pose = robot_pose_from_marker(pixels(marker, truth), marker, CAMERA, MOUNT)
    assert pose.distance_to(truth) < 0.01
    assert math.degrees(pose.yaw_error(truth)) < 0.1


def test_the_level_pose_fit_never_takes_the_mirror_of_a_far_tag() -> None:
    """A 20 cm tag 4-5 m away, nearly head-on, with 0.3 px corner noise: the 6-DOF solutions scatter
    (one of IPPE's two is the tilted mirror); the level 3-DOF fit stays within decimetres."""
    marker = Marker(3, 4.0, -2.0, 1.1, (0.0, 1.0), math.pi / 2)
    rng = np.random.default_rng(5)
    errors = []
    for _ in range(40):
        d = rng.uniform(4.0, 5.0)
        a = marker.yaw + math.radians(rng.uniform(-12.0, 12.0))
        cam = np.array([marker.x, marker.y]) + d * np.array([math.cos(a), math.sin(a)])
        yaw = a + math.pi + math.radians(rng.uniform(-5.0, 5.0))
        truth = Pose2D(cam[0] - MOUNT.x * math.cos(yaw), cam[1] - MOUNT.x * math.sin(yaw), yaw)
        corners = pixels(marker, truth) + rng.normal(0.0, 0.3, (4, 2))
        errors.append(robot_pose_from_marker(corners, marker, CAMERA, MOUNT).distance_to(truth))
    assert max(errors) < 1.0
    assert float(np.median(errors)) < 0.3
