"""initcli.core.navigation.feature_walls: across an open floor to the wall where the hypotheses put a feature
not yet seen."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.navigation.feature_walls import FEATURE_WALL_SEEN, toward_feature_wall, toward_long_wall
from initcli.core.navigation.wall_following import ScanView

ANGLES = np.linspace(-math.pi, math.pi, 360, endpoint=False)
# A hall 20 m wide: the robot 0.7 m from its left wall (y = 0.7), the far wall at y = -12, the ends at
# x = -8 and x = 14.
HALL_WALLS = [
    (-8.0, 0.7, 14.0, 0.7),
    (-8.0, -12.0, 14.0, -12.0),
    (-8.0, -12.0, -8.0, 0.7),
    (14.0, -12.0, 14.0, 0.7),
]


def hall() -> ScanView:
    ranges = ray_segment_distances(np.zeros(2), ANGLES, np.array(HALL_WALLS, dtype=float), 20.0)
    return ScanView.of(ANGLES, ranges, 20.0)


def test_the_way_leads_to_the_wall_that_holds_the_most_hypotheses_features() -> None:
    # hypothesis 0 and 1 put a door on the far wall straight across (facing the robot), hypothesis 2
    # one on the end wall ahead
    points = np.array([[0.5, -11.9], [-0.5, -11.9], [13.9, -5.0]])
    normals = np.array([[0.0, 1.0], [0.0, 1.0], [-1.0, 0.0]])
    way = toward_feature_wall(hall(), points, normals, np.array([0, 1, 2]))
    assert way is not None
    bearing, reach, hypotheses = way
    assert hypotheses == 2 and abs(math.degrees(bearing) + 90.0) <= 10.0 + 1e-6
    assert 8.0 < reach < 11.0  # stops short of the far wall
    # only the end wall's door left: the way turns there
    alone = toward_feature_wall(hall(), points[2:], normals[2:], np.array([2]))
    assert alone is not None and abs(math.degrees(alone[0])) <= 40.0 and alone[2] == 1


def test_no_way_for_features_facing_away_near_the_robot_or_where_a_crossing_went() -> None:
    far_wall = np.array([[0.0, -11.9]])
    assert toward_feature_wall(hall(), far_wall, np.array([[0.0, -1.0]]), np.array([0])) is None  # its back
    near = np.array([[0.0, -0.5 * FEATURE_WALL_SEEN]])
    assert toward_feature_wall(hall(), near, np.array([[0.0, 1.0]]), np.array([0])) is None
    way = toward_feature_wall(hall(), far_wall, np.array([[0.0, 1.0]]), np.array([0]))
    assert way is not None
    end = way[1] * np.array([math.cos(way[0]), math.sin(way[0])])
    again = toward_feature_wall(hall(), far_wall, np.array([[0.0, 1.0]]), np.array([0]), been=end[None])
    assert (
        again is None
        or math.hypot(*(again[1] * np.array([math.cos(again[0]), math.sin(again[0])]) - end)) > 3.0
    )
    assert toward_feature_wall(hall(), np.empty((0, 2)), np.empty((0, 2)), np.empty(0)) is None


def test_no_way_to_a_feature_the_path_drove_past_nor_to_a_column() -> None:
    door, facing = np.array([[0.0, -11.9]]), np.array([[0.0, 1.0]])
    assert toward_feature_wall(hall(), door, facing, np.array([0])) is not None
    # the path went by 2 m in front of the door (in view), or behind it (not): only in front counts
    in_front, behind = np.array([[3.0, -10.0]]), np.array([[0.0, -14.0]])
    assert toward_feature_wall(hall(), door, facing, np.array([0]), passed=in_front) is None
    assert toward_feature_wall(hall(), door, facing, np.array([0]), passed=behind) is not None
    # a column 0.6 m wide across the floor, a door predicted beside it: no wall to follow on there
    column = [
        (-0.3, -6.0, 0.3, -6.0),
        (0.3, -6.0, 0.3, -6.6),
        (0.3, -6.6, -0.3, -6.6),
        (-0.3, -6.6, -0.3, -6.0),
    ]
    open_floor = np.array([(-40.0, 0.7, 40.0, 0.7), *column], dtype=float)  # the far wall beyond the lidar
    ranges = ray_segment_distances(np.zeros(2), ANGLES, open_floor, 20.0)
    columns = ScanView.of(ANGLES, ranges, 20.0)
    assert toward_feature_wall(columns, np.array([[0.0, -6.5]]), facing, np.array([0])) is None


def test_the_nearest_long_wall_the_path_has_not_followed() -> None:
    # the path followed the end wall (x = -8) up and the left wall to here
    up_the_end = [[-7.3, y] for y in np.arange(-11.3, 0.0, 0.5)]
    along = np.array(up_the_end + [[x, 0.0] for x in np.arange(-7.3, 0.1, 0.5)])
    way = toward_long_wall(hall(), along)
    assert way is not None  # not the followed walls: the far one, straight across
    assert abs(math.degrees(way[0]) + 90.0) <= 10.0 + 1e-6 and 9.0 < way[1] < 11.0
    fresh = toward_long_wall(hall(), np.array([[-30.0, 0.0]]))  # the path far off: a nearer one
    assert fresh is not None and fresh[1] < way[1] - 1.0
    column = [
        (-0.3, -3.0, 0.3, -3.0),
        (0.3, -3.0, 0.3, -3.6),
        (0.3, -3.6, -0.3, -3.6),
        (-0.3, -3.6, -0.3, -3.0),
    ]
    ranges = ray_segment_distances(np.zeros(2), ANGLES, np.array([(-40.0, 0.7, 40.0, 0.7), *column]), 20.0)
    assert toward_long_wall(ScanView.of(ANGLES, ranges, 20.0), along) is None  # only a column
