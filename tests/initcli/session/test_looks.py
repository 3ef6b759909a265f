"""initcli.session.looks: a look turns all the way round; along a wall with open space beside the
robot looks again every look_every m without a new feature, and crosses the floor after cross_after
such looks."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from initcli.config.session import ExplorationSection
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.wall_following import ScanView, WallFollowParams
from initcli.drivers.base import SensorFrame
from initcli.session.escapes import Escapes
from initcli.session.looks import Looks
from initcli.session.result import SessionResult

EXPLORATION = ExplorationSection()
ANGLES = np.linspace(-math.pi, math.pi, 360, endpoint=False)


def scan_of(segments: list[tuple[float, float, float, float]]) -> ScanView:
    """The scan at the origin, heading +x, among ``segments`` (x1, y1, x2, y2)."""
    ranges = ray_segment_distances(np.zeros(2), ANGLES, np.array(segments, dtype=float), 20.0)
    return ScanView.of(ANGLES, ranges, 20.0)


HALL = scan_of([(-30.0, 0.7, 30.0, 0.7), (-30.0, -9.0, 30.0, -9.0)])  # the left wall, open to the right
CORRIDOR = scan_of([(-30.0, 0.7, 30.0, 0.7), (-30.0, -1.3, 30.0, -1.3)])


def test_a_look_is_done_once_it_turned_all_the_way_round() -> None:
    looks = Looks(EXPLORATION)
    looks.begin()
    pose = Pose2D(0.0, 0.0, 0.0)
    steps = 0
    while not looks.done:
        turned = Pose2D(0.0, 0.0, pose.yaw + 0.06)
        looks.moved(pose, turned)
        pose, steps = turned, steps + 1
    assert math.isclose(looks.turned, 0.06 * steps) and 0.06 * (steps - 1) < math.radians(EXPLORATION.turn)
    half = Looks(dataclasses.replace(EXPLORATION, turn=180.0))
    half.moved(Pose2D(0.0, 0.0, 0.0), Pose2D(0.0, 0.0, math.pi))
    assert half.done


def test_the_robot_looks_again_only_with_open_space_beside_and_far_enough_on() -> None:
    looks = Looks(EXPLORATION)
    every = EXPLORATION.look_every
    assert not looks.again(every - 0.1, HALL, side=1)
    assert not looks.again(every + 0.1, CORRIDOR, side=1)  # both walls in view already
    assert looks.again(every + 0.1, HALL, side=1) and looks.open_floor and looks.count == 1
    assert not looks.again(2 * every, HALL, side=1)  # the next one look_every m after this one
    looks.new_feature(2 * every)
    assert not looks.again(3 * every - 0.1, HALL, side=1) and looks.again(3 * every + 0.2, HALL, side=1)
    never = Looks(dataclasses.replace(EXPLORATION, look_every=0.0))
    assert not never.again(1000.0, HALL, side=1)


def test_the_floor_is_crossed_after_cross_after_fruitless_looks() -> None:
    result = SessionResult(False, "", None)
    x = EXPLORATION
    escapes = Escapes(x.loops, x.shuttles, x.frontier, x.laps, x.long_walls, WallFollowParams(), result)
    looks = Looks(dataclasses.replace(EXPLORATION, cross_after=2))
    frame = SensorFrame(1.0, Pose2D(0.0, 0.0, 0.0))
    assert looks.cross(frame, HALL, 1, escapes, travel=20.0) is None and result.crossings == 0
    crossing = looks.cross(frame, HALL, 1, escapes, travel=30.0)
    assert crossing is not None and result.crossings == 1 and looks.fruitless == 0
    assert looks.look_from == 30.0 + crossing.reach  # the next look comes look_every m past the crossing
    # a new feature starts the count again
    looks.cross(frame, HALL, 1, escapes, travel=40.0)
    looks.new_feature(41.0)
    assert looks.cross(frame, HALL, 1, escapes, travel=50.0) is None
    off = Looks(dataclasses.replace(EXPLORATION, cross_after=0))
    assert all(off.cross(frame, HALL, 1, escapes, travel=60.0) is None for _ in range(5))


def test_with_hypotheses_a_fruitless_look_crosses_to_the_wall_that_holds_their_features() -> None:
    result = SessionResult(False, "", None)
    x = EXPLORATION
    escapes = Escapes(x.loops, x.shuttles, x.frontier, x.laps, x.long_walls, WallFollowParams(), result)
    looks = Looks(dataclasses.replace(EXPLORATION, feature_walls=True))  # cross_after 6: none yet without
    frame = SensorFrame(1.0, Pose2D(0.0, 0.0, 0.0))
    door = (np.array([[0.0, -8.9]]), np.array([[0.0, 1.0]]), np.array([0]))  # on the far wall, facing us
    crossing = looks.cross(frame, HALL, 1, escapes, travel=20.0, predicted=door)
    assert crossing is not None and result.crossings == 1 and 5.0 < crossing.reach < 8.0
    assert looks.cross(frame, HALL, 1, escapes, travel=30.0, predicted=door) is None  # been there
    off = Looks(dataclasses.replace(EXPLORATION, feature_walls=False))
    assert off.cross(frame, HALL, 1, escapes, travel=20.0, predicted=door) is None
