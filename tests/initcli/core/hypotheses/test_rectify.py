"""BIM rectification (Eq. 17) against hand-computed cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.rectify import WallArray, nearest_wall, rectify_pose, rectify_position

# Corridor: bottom wall y = 0 (free space above), top wall y = 2 (free space below).
WALLS = WallArray.from_segments([(0.0, 0.0, 10.0, 0.0, 0.0, 1.0), (0.0, 2.0, 10.0, 2.0, 0.0, -2.0)])


DOOR = np.array([6.0, 0.0])


def test_nearest_wall_by_perpendicular_distance() -> None:
    assert nearest_wall(np.array([4.0, 0.3]), WALLS) == (0, pytest.approx(0.3))
    assert nearest_wall(np.array([4.0, 1.8]), WALLS) == (1, pytest.approx(0.2))
    assert nearest_wall(np.array([12.0, 1.0]), WALLS)[0] == -1  # beyond both segments
    assert WALLS.normal[1] == pytest.approx([0.0, -1.0])  # normals are normalised


def test_eq17_hand_computed() -> None:
    # (x_g, y_g) = (4, 0.2) is 0.2 m from the wall: moved out to y = 0.5, then along the wall to the point
    # 2.5 m from the door (6, 0): (x - 6)^2 + 0.5^2 = 2.5^2 -> x = 6 - sqrt(6) (the root nearer x_adj = 4).
    rect = rectify_position(np.array([4.0, 0.2]), WALLS, 0.5, DOOR, 2.5)
    assert rect.moved and rect.wall == 0 and rect.d_wall == pytest.approx(0.2)
    assert rect.position == pytest.approx([6.0 - math.sqrt(6.0), 0.5])


def test_eq17_inside_the_wall_and_far_enough() -> None:
    inside = rectify_position(np.array([4.0, -0.1]), WALLS, 0.5, DOOR, 2.5)
    assert inside.position == pytest.approx([6.0 - math.sqrt(6.0), 0.5])
    clear = rectify_position(np.array([4.0, 1.0]), WALLS, 0.5, DOOR, 2.5)
    assert not clear.moved and clear.position == pytest.approx([4.0, 1.0])


def test_eq17_circle_not_reaching_the_line() -> None:
    # d_o = 0.3 < 0.5: no point of the clearance line is 0.3 m from the door; the nearest one is (6, 0.5).
    rect = rectify_position(np.array([5.5, 0.1]), WALLS, 0.5, DOOR, 0.3)
    assert rect.position == pytest.approx([6.0, 0.5])


def test_rectify_pose_recomputes_heading_with_eq13() -> None:
    pose = Pose2D(4.0, 0.2, 0.3)
    feature_robot = np.array([2.5, 0.0])  # the door straight ahead, 2.5 m away
    new, rect = rectify_pose(pose, WALLS, 0.5, DOOR, feature_robot)
    assert rect.moved
    assert (new.x, new.y) == pytest.approx((6.0 - math.sqrt(6.0), 0.5))
    assert new.yaw == pytest.approx(math.atan2(-0.5, math.sqrt(6.0)))
    same, rect = rectify_pose(Pose2D(4.0, 1.0, 0.3), WALLS, 0.5, DOOR, feature_robot)
    assert not rect.moved and same == Pose2D(4.0, 1.0, 0.3)


def test_a_rectification_that_turns_the_pose_past_max_turn_is_dropped() -> None:
    # The door seen close behind on the left (robot frame (-0.2, 0.25)) from a pose 0.05 m off the
    # wall just past it: moved out to the clearance line, the circle of d_o = 0.32 m does not reach
    # it, the point nearest the door is (6, 0.5), and Eq. 13 there turns the heading by 141 degrees.
    pose = Pose2D(6.3, 0.05, 0.0)
    feature_robot = np.array([-0.2, 0.25])
    turned, rect = rectify_pose(pose, WALLS, 0.5, DOOR, feature_robot)
    assert rect.moved and abs(turned.yaw_error(pose)) > math.radians(15.0)
    kept, rect = rectify_pose(pose, WALLS, 0.5, DOOR, feature_robot, max_turn=math.radians(15.0))
    assert not rect.moved and kept == pose
    # a small turn stays allowed (-0.2 rad to atan2(-0.5, sqrt(6)), under 1 degree)
    small, rect = rectify_pose(Pose2D(4.0, 0.2, -0.2), WALLS, 0.5, DOOR, np.array([2.5, 0.0]), 0.26)
    assert rect.moved and (small.x, small.y) == pytest.approx((6.0 - math.sqrt(6.0), 0.5))
