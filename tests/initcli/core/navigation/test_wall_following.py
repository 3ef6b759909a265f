"""Wall following (initcli.core.navigation.wall_following) on a simulated lidar in a small corridor."""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.navigation.wall_following import ScanView, WallFollowParams, wall_follow

PARAMS = WallFollowParams(front_stop=0.5)  # a robot of radius 0.3 m, as the session sets it
RADIUS = 0.3
BEAMS = np.radians(np.arange(-180.0, 180.0, 1.0))


def _box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


def _corridor(width: float, stack_depth: float) -> np.ndarray:
    """A corridor along +x, 16 m long and ``width`` wide (walls at y = 0 and y = width), closed at
    both ends, with a 1.2 m long material stack ``stack_depth`` deep against the left wall at x = 8."""
    segments = [[-1.0, 0.0, 16.0, 0.0], [-1.0, width, 16.0, width], [-1.0, 0.0, -1.0, width]]
    segments += [[16.0, 0.0, 16.0, width]]
    if stack_depth > 0:
        segments += _box(8.0, width - stack_depth, 9.2, width)
    return np.array(segments, dtype=float)


def _drive(segments: np.ndarray, start: tuple[float, float, float], steps: int = 400) -> np.ndarray:
    """Follow the left wall from ``start`` at 10 Hz; the (x, y) path."""
    x, y, yaw = start
    path = []
    for _ in range(steps):
        ranges = ray_segment_distances(np.array([x, y]), yaw + BEAMS, segments, 20.0)
        v, w = wall_follow(ScanView.of(BEAMS, ranges, 20.0), +1, PARAMS)
        yaw += 0.1 * w
        x, y = x + 0.1 * v * math.cos(yaw), y + 0.1 * v * math.sin(yaw)
        path.append((x, y))
    return np.array(path)


def _clearance(segments: np.ndarray, path: np.ndarray) -> float:
    ranges = [ray_segment_distances(p, BEAMS, segments, 20.0).min() for p in path]
    return float(min(ranges))


def test_follows_the_wall_at_its_distance_down_a_wide_corridor() -> None:
    segments = _corridor(3.0, 0.0)
    path = _drive(segments, (0.0, 2.3, 0.0), steps=200)
    assert path[-1, 0] > 8.0  # 10 s at up to 0.5 m/s
    assert abs(path[-1, 1] - (3.0 - PARAMS.distance)) < 0.1


def test_passes_a_stack_that_leaves_a_gap_narrower_than_twice_the_wall_distance() -> None:
    """A 1.8 m corridor with a 0.65 m stack on the followed wall leaves 1.15 m: the robot (0.6 m
    wide) keeps to the middle of the gap and drives on, where keeping 0.7 m from the stack would push
    it into the far wall and turn it back."""
    segments = _corridor(1.8, 0.65)
    path = _drive(segments, (0.0, 1.1, 0.0))
    assert path[:, 0].max() > 12.0  # past the stack (x 8-9.2) ...
    assert _clearance(segments, path) > RADIUS  # ... without touching anything


def test_scan_view_keeps_each_beam_layouts_directions_and_gives_the_same_front() -> None:
    """ScanView.of takes the beams' cosines from its per-layout cache: the end points, and so the
    distance ahead, are those computed from the angles themselves, and a new layout is not served
    an old one's directions."""
    rng = np.random.default_rng(5)
    for offset in (0.0, 0.0, 2 * math.pi, 0.3):  # repeated layouts and new ones
        angles = BEAMS + offset
        ranges = rng.uniform(0.3, 6.0, len(BEAMS))
        ranges[rng.random(len(BEAMS)) < 0.1] = np.inf
        view = ScanView.of(angles, ranges, 20.0)
        plain = ScanView(view.angles, view.ranges)  # no cached directions: cos/sin of the angles
        assert view.cos is not None and view.sin is not None
        np.testing.assert_array_equal(view.cos, np.cos(view.angles))
        for half_width in (0.2, 0.35, 1.0):
            assert view.front(half_width) == plain.front(half_width)


def _scan_at(segments: list[list[float]], x: float = 0.0, y: float = 0.0, yaw: float = 0.0) -> ScanView:
    ranges = ray_segment_distances(np.array([x, y]), yaw + BEAMS, np.array(segments, dtype=float), 20.0)
    return ScanView.of(BEAMS, ranges, 20.0)


def test_clear_along_a_bearing_is_the_front_turned_that_way() -> None:
    """A wall 0.7 m to the left and one 5 m to the right: free 0.7 m to the left, 5 m to the right,
    and straight ahead the front (nothing up to the lidar's range)."""
    scan = _scan_at([[-30.0, 0.7, 30.0, 0.7], [-30.0, -5.0, 30.0, -5.0]])
    assert math.isclose(scan.clear_along(math.pi / 2), 0.7, abs_tol=0.02)
    assert math.isclose(scan.clear_along(-math.pi / 2), 5.0, abs_tol=0.02)
    assert scan.clear_along(0.0) == scan.front() == math.inf


def test_across_the_floor_heads_square_across_the_open_side_to_short_of_the_far_wall() -> None:
    """The façade followed on the left, the rooms in the middle 11 m to the right: square across,
    stopping CROSS_SHORT short; mirrored for the right wall; a corridor (2.5 m) is no open floor."""
    from initcli.core.navigation.wall_following import CROSS_SHORT, across_the_floor

    hall = [[-30.0, 0.7, 30.0, 0.7], [-30.0, -11.0, 30.0, -11.0]]
    bearing, reach = across_the_floor(_scan_at(hall), +1) or (0.0, 0.0)
    assert math.isclose(bearing, -math.pi / 2) and math.isclose(reach, 11.0 - CROSS_SHORT, abs_tol=0.05)
    mirrored = [[-30.0, -0.7, 30.0, -0.7], [-30.0, 11.0, 30.0, 11.0]]
    bearing, reach = across_the_floor(_scan_at(mirrored), -1) or (0.0, 0.0)
    assert math.isclose(bearing, math.pi / 2) and math.isclose(reach, 11.0 - CROSS_SHORT, abs_tol=0.05)
    assert across_the_floor(_scan_at([[-30.0, 0.7, 30.0, 0.7], [-30.0, -2.5, 30.0, -2.5]]), +1) is None


def test_across_the_floor_takes_the_way_that_gets_farthest_to_a_wall() -> None:
    """A room's wall 4 m to the right with an opening ahead-right and a wall 10 m across behind it:
    the crossing goes through the opening (farthest from the followed wall of its bearings)."""
    from initcli.core.navigation.wall_following import CROSS_SHORT, across_the_floor

    room = [[-30.0, 0.7, 30.0, 0.7], [-30.0, -4.0, 1.0, -4.0], [7.0, -4.0, 30.0, -4.0]]
    bearing, reach = across_the_floor(_scan_at([*room, [-30.0, -10.0, 30.0, -10.0]]), +1) or (0.0, 0.0)
    assert -math.radians(70) < bearing < -math.radians(40)  # through the opening ...
    assert math.isclose(-math.sin(bearing) * (reach + CROSS_SHORT), 10.0, abs_tol=0.5)  # ... to the far wall
    bearing, reach = across_the_floor(_scan_at(room), +1) or (0.0, 0.0)  # the opening leads nowhere seen
    assert math.isclose(bearing, -math.pi / 2) and math.isclose(reach, 4.0 - CROSS_SHORT, abs_tol=0.05)


def test_across_the_floor_needs_a_wall_not_a_column_nor_the_void() -> None:
    """Across a car park only a column (0.5 m) stands 5 m away, or a row of them 3.5 m apart, or
    nothing within the lidar's reach: no crossing (the robot would circle a column or stop in the
    middle of nowhere)."""
    from initcli.core.navigation.wall_following import across_the_floor

    def column(x: float) -> list[list[float]]:
        return [
            [x - 0.25, -5.0, x + 0.25, -5.0],
            [x + 0.25, -5.0, x + 0.25, -5.5],
            [x + 0.25, -5.5, x - 0.25, -5.5],
        ]

    assert across_the_floor(_scan_at([[-30.0, 0.7, 30.0, 0.7], *column(0.0)]), +1) is None
    row = [side for x in np.arange(-14.0, 15.0, 3.5) for side in column(float(x))]  # a row of them
    assert across_the_floor(_scan_at([[-30.0, 0.7, 30.0, 0.7], *row]), +1) is None
    assert across_the_floor(_scan_at([[-30.0, 0.7, 30.0, 0.7]]), +1) is None
