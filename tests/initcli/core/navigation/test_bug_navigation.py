"""The bug navigator: round a stack on the open side, back when the wall leads away."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.bug_navigation import BugNavigator, BugParams, around_side
from initcli.core.navigation.wall_following import ScanView
from initcli.storey.outlines import box_edges


def scan_of(points: np.ndarray) -> ScanView:
    """A 360-beam scan from the origin (robot facing +x) against the given wall segments."""
    from initcli.core.geometry.raycast import ray_segment_distances

    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    ranges = ray_segment_distances(np.zeros(2), angles, points, 20.0)
    return ScanView.of(angles, ranges, 20.0)


def corridor_with_stack(stack_on_left: bool) -> np.ndarray:
    walls = np.array([[-5.0, 0.9, 20.0, 0.9], [-5.0, -0.9, 20.0, -0.9]])
    y = 0.65 if stack_on_left else -0.65
    stack = box_edges(0.8, y, 0.6, 0.25)
    return np.vstack([walls, stack])


def test_bug_goes_round_a_stack_on_the_open_side():
    # target straight ahead, slightly to the side of the stack: the open side still wins
    assert around_side(scan_of(corridor_with_stack(stack_on_left=True)), d_yaw=0.05) == 1
    assert around_side(scan_of(corridor_with_stack(stack_on_left=False)), d_yaw=-0.05) == -1
    # nothing to choose between: the target's side
    open_room = np.array([[2.0, -5.0, 2.0, 5.0]])
    assert around_side(scan_of(open_room), d_yaw=0.3) == -1
    assert around_side(scan_of(open_room), d_yaw=-0.3) == 1


def test_bug_turns_back_when_the_wall_leads_away_from_the_target():
    nav = BugNavigator(np.array([10.0, 0.0]), BugParams())
    nav.mode, nav.side, nav.hit_distance, nav.give_up_at = "follow", 1, 10.0, 11.5
    scan = scan_of(np.array([[-5.0, 0.9, 20.0, 0.9], [-5.0, -0.9, 20.0, -0.9]]))
    nav.step(Pose2D(-2.0, 0.0, math.pi), scan)  # 12 m away: the wrong way round
    assert nav.side == -1 and nav.flipped and nav.mode == "follow"
    nav.step(Pose2D(-4.0, 0.0, math.pi), scan)  # the other side leads away too: head for it
    assert nav.mode == "go"
