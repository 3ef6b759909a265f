"""initcli.session.escapes: loops and shuttling are seen on the odometry path, and the robot drives out
of them (toward an unexplored opening, else open space), or across an open floor."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from initcli.config.exploration import FrontierSettings, LapSettings, LoopSettings, ShuttleSettings
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.bug_navigation import BugNavigator, BugParams
from initcli.core.navigation.wall_following import ScanView, WallFollowParams
from initcli.drivers.base import LaserScan, SensorFrame
from initcli.session.escapes import Escapes, open_point
from initcli.session.result import SessionResult, ShutIn

LOOPS, SHUTTLES, FRONTIER = LoopSettings(), ShuttleSettings(), FrontierSettings()
ANGLES = np.linspace(-math.pi, math.pi, 360, endpoint=False)


def escapes(
    loops: LoopSettings = LOOPS, shuttles: ShuttleSettings = SHUTTLES, to_long_walls: bool = False
) -> tuple[Escapes, SessionResult]:
    """Escapes with these settings (out of a circle round a column to a long wall: ``to_long_walls``)."""
    result = SessionResult(False, "", None)
    return Escapes(
        loops, shuttles, FRONTIER, LapSettings(), to_long_walls, WallFollowParams(), result
    ), result


def scan_of(
    segments: list[tuple[float, float, float, float]], at: Pose2D, range_max: float = 20.0
) -> LaserScan:
    """The lidar's ranges at ``at`` (odom = world here) among ``segments`` (x1, y1, x2, y2)."""
    world = ANGLES + at.yaw
    ranges = ray_segment_distances(np.array([at.x, at.y]), world, np.array(segments, dtype=float), range_max)
    return LaserScan(float(ANGLES[0]), float(ANGLES[1] - ANGLES[0]), range_max, ranges)


def view(scan: LaserScan) -> ScanView:
    return ScanView.of(scan.angles, scan.ranges, scan.range_max)


def test_a_slow_circle_is_a_loop_and_a_straight_drive_is_not() -> None:
    """The wall follower with no wall in reach arcs on its 0.7 m radius at 0.3 m/s (Office_A's open
    plan): a loop within ``loops.window`` seconds; the same speed down a corridor is none."""
    circling, _ = escapes()
    hits = [
        k / 10.0
        for k in range(int(2 * LOOPS.window * 10))
        if circling.looping(
            SensorFrame(k / 10.0, Pose2D(0.7 * math.cos(0.3 * k / 7), 0.7 * math.sin(0.3 * k / 7), 0.0))
        )
    ]
    assert hits and hits[0] <= LOOPS.window + 2.0
    straight, _ = escapes()
    assert not any(straight.looping(SensorFrame(k / 10.0, Pose2D(0.03 * k, 0.0, 0.0))) for k in range(900))
    # a looser loop setting (a longer path in the window) does not call the circle a loop
    lax, _ = escapes(dataclasses.replace(LOOPS, length=100.0))
    assert not any(
        lax.looping(
            SensorFrame(k / 10.0, Pose2D(0.7 * math.cos(0.3 * k / 7), 0.7 * math.sin(0.3 * k / 7), 0.0))
        )
        for k in range(900)
    )


def test_shuttling_is_a_long_drive_that_stays_in_a_wide_circle() -> None:
    """Back and forth over 6 m at 0.5 m/s: shuttling within ``shuttles.window``, not a loop (wider)."""
    watch, _ = escapes()
    frames = [
        SensorFrame(k / 10.0, Pose2D(3.0 * math.sin(k / 60.0), 0.0, 0.0))
        for k in range(int(SHUTTLES.window * 10) + 50)
    ]
    assert any(watch.shuttling(f) for f in frames)
    short, _ = escapes(shuttles=dataclasses.replace(SHUTTLES, radius=1.0))
    assert not any(short.shuttling(f) for f in frames)


def test_the_open_point_lies_along_the_longest_free_beam_short_of_what_it_hit() -> None:
    at = Pose2D(1.0, 2.0, math.pi / 2)
    # A room 4 m deep ahead (robot frame x), 12 m to the left: the longest beam points left.
    scan = view(scan_of([(-10.0, 6.0, 10.0, 6.0), (-11.0, -10.0, -11.0, 10.0)], at))
    point = open_point(SensorFrame(0.0, at), scan, LOOPS)
    assert math.hypot(point[0] - at.x, point[1] - at.y) == pytest.approx(LOOPS.open_reach)
    near = dataclasses.replace(LOOPS, open_reach=100.0, open_short=2.0)
    far = open_point(SensorFrame(0.0, at), scan, near)  # the longest beam, 2 m short of the wall it hit
    assert float(np.max(scan.ranges)) - 2.0 == pytest.approx(math.hypot(far[0] - at.x, far[1] - at.y))
    blind = open_point(SensorFrame(0.0, at), None, LOOPS)  # no scan: straight ahead
    assert blind == pytest.approx([at.x, at.y + LOOPS.blind_reach])


def test_an_escape_steers_for_its_time_and_is_counted() -> None:
    e, result = escapes()
    frame = SensorFrame(10.0, Pose2D(0.0, 0.0, 0.0))
    assert not e.under_way(frame)
    e.start(frame, BugNavigator(np.array([5.0, 0.0]), BugParams(follow=WallFollowParams())))
    assert result.loop_escapes == 1
    assert e.under_way(SensorFrame(10.0 + LOOPS.escape - 0.1, frame.odom))
    assert not e.under_way(SensorFrame(10.0 + LOOPS.escape, frame.odom))
    # no loop is seen while the escape steers
    assert not e.looping(SensorFrame(10.0 + LOOPS.escape - 0.1, frame.odom))
    open_floor = view(scan_of([(-30.0, 9.0, 30.0, 9.0), (-30.0, -9.0, 30.0, -9.0)], frame.odom))
    v, _ = e.step(frame, open_floor)
    assert v > 0.0 and e.navigator is not None
    v, _ = e.step(SensorFrame(11.0, Pose2D(5.0, 0.0, 0.0)), open_floor)  # there: it ends
    assert e.navigator is None
    e.cancel()
    assert not e.under_way(frame)


def test_out_of_a_loop_toward_an_unexplored_opening_the_lidar_has_seen() -> None:
    """A corridor 2 m wide along x, closed behind the robot, open ahead beyond the lidar's reach:
    with nothing integrated there is no opening to head for (the escape heads for open space); once
    the scans are in the local map the escape takes the route to the opening."""
    e, result = escapes()
    at = Pose2D(0.0, 0.0, 0.0)
    corridor = [(-1.0, -1.0, 40.0, -1.0), (-1.0, 1.0, 40.0, 1.0), (-1.0, -1.0, -1.0, 1.0)]
    scan = scan_of(corridor, at, range_max=20.0)
    frame = SensorFrame(0.0, at, scan)
    assert not e.head_for_frontier(frame) and result.loop_escapes == 0
    e.out_of_loop(frame, view(scan))  # open space: along the corridor
    assert result.loop_escapes == 1 and isinstance(e.navigator, BugNavigator)
    for step in range(3 * FRONTIER.scan_every):
        e.see(SensorFrame(step / 10.0, at, scan), step)
    assert e.head_for_frontier(frame) and result.loop_escapes == 2
    why = e.after_shuttling(frame, side=-1, exploring=True)
    assert (
        why
        == "shuttling over the same ground; heading for an unexplored opening, then following the right wall"
    )
    assert (
        e.after_shuttling(frame, side=1, exploring=False)
        == "shuttling over the same ground; following the left wall"
    )
    assert result.loop_escapes == 3  # the one for exploring only


def test_a_crossing_drives_to_the_wall_across_the_open_floor() -> None:
    """Following the left wall (0.7 m away) in a hall whose far wall stands 9 m to the right: the
    crossing heads right, stopping short of that wall, and steers until its time is up."""
    e, result = escapes()
    at = Pose2D(0.0, 0.0, 0.0)
    hall = [(-30.0, 0.7, 30.0, 0.7), (-30.0, -9.0, 30.0, -9.0)]
    frame = SensorFrame(5.0, at)
    crossing = e.cross(frame, view(scan_of(hall, at)), side=1)
    assert crossing is not None and result.crossings == 1 and result.loop_escapes == 0
    assert 5.0 < crossing.reach < 9.0
    assert e.under_way(SensorFrame(5.0 + crossing.seconds - 0.1, at))
    assert not e.under_way(SensorFrame(5.0 + crossing.seconds, at))
    corridor = [(-30.0, 0.7, 30.0, 0.7), (-30.0, -1.3, 30.0, -1.3)]
    assert e.cross(frame, view(scan_of(corridor, at)), side=1) is None and result.crossings == 1


def _lap_in(
    walls: list[tuple[float, float, float, float]],
    path: list[tuple[float, float]],
    seen_from: list[tuple[float, float]] = (),
    to_long_walls: bool = False,
):
    """Integrate the scans from ``seen_from`` and along ``path`` (odom = world) among ``walls`` into
    the local map, then drive ``path`` as the lap watch sees it, 0 features: what
    :meth:`Escapes.lap` returns."""
    return lap_in(*escapes(to_long_walls=to_long_walls), walls, path, seen_from)


def lap_in(
    e: Escapes,
    result: SessionResult,
    walls: list[tuple[float, float, float, float]],
    path: list[tuple[float, float]],
    seen_from: list[tuple[float, float]] = (),
):
    """:func:`_lap_in` with the escapes ``e`` that count in ``result``."""
    poses = [Pose2D(x, y, 0.0) for x, y in path]
    for step, at in enumerate([Pose2D(x, y, 0.0) for x, y in seen_from] + poses):
        e.see(SensorFrame(0.1 * step, at, scan_of(walls, at)), step * e.frontier.scan_every)
    travel, why = 0.0, None
    for k, at in enumerate(poses):
        travel += 0.0 if k == 0 else math.hypot(at.x - poses[k - 1].x, at.y - poses[k - 1].y)
        result.odom_path.append(at.as_tuple())
        got = e.lap(SensorFrame(100.0 + 0.1 * k, at, scan_of(walls, at)), travel, 0)
        why = why or got
    return why, result


def test_a_circle_in_a_closed_hall_is_not_shut_in_a_lap_round_a_closed_room_is() -> None:
    """Both spaces are closed (no opening on the local map). Round the 5 x 6 m room, 0.7 m from its
    walls, the lap encloses most of what the lidar saw: shut in. A 1.3 m circle in a 20 x 14 m hall
    (the wall follower lost its wall) encloses a twentieth of it: not shut in, only a circle."""
    room = [(0.0, 0.0, 5.0, 0.0), (5.0, 0.0, 5.0, 6.0), (5.0, 6.0, 0.0, 6.0), (0.0, 6.0, 0.0, 0.0)]
    corners = [(0.7, 0.7), (4.3, 0.7), (4.3, 5.3), (0.7, 5.3), (0.7, 0.7), (1.5, 0.7)]
    lap_path = [
        (x0 + (x1 - x0) * t / 10, y0 + (y1 - y0) * t / 10)
        for (x0, y0), (x1, y1) in zip(corners[:-1], corners[1:], strict=True)
        for t in range(10)
    ]
    shut, _ = _lap_in(room, lap_path)
    assert isinstance(shut, ShutIn) and shut.features == 0
    hall = [(0.0, 0.0, 20.0, 0.0), (20.0, 0.0, 20.0, 14.0), (20.0, 14.0, 0.0, 14.0), (0.0, 14.0, 0.0, 0.0)]
    circle = [
        (10.0 + 1.3 * math.cos(a * math.pi / 20), 7.0 + 1.3 * math.sin(a * math.pi / 20)) for a in range(46)
    ]
    everywhere = [(x, y) for x in np.arange(2.0, 19.0, 2.0) for y in np.arange(2.0, 13.0, 2.0)]
    why, result = _lap_in(hall, circle, everywhere)
    assert why == "a 7 m circle without a new feature on an open floor" and result.laps == 0
    assert result.crossings == 0


COLUMN = [(9.7, 4.7, 10.3, 4.7), (10.3, 4.7, 10.3, 5.3), (10.3, 5.3, 9.7, 5.3), (9.7, 5.3, 9.7, 4.7)]
HALL = [(0.0, 0.0, 20.0, 0.0), (20.0, 0.0, 20.0, 14.0), (20.0, 14.0, 0.0, 14.0), (0.0, 14.0, 0.0, 0.0)]
ROUND_THE_COLUMN = [(10.0 + math.cos(a * math.pi / 20), 5.0 + math.sin(a * math.pi / 20)) for a in range(46)]
ALL_OVER_THE_HALL = [(x, y) for x in np.arange(2.0, 19.0, 2.0) for y in np.arange(2.0, 13.0, 2.0)]


def test_out_of_a_circle_round_a_column_to_the_nearest_long_wall() -> None:
    """exploration.long_walls: round a column in the middle of a 20 x 14 m hall (the wall
    follower took it for a wall) the robot heads for the nearest long wall, the hall's south wall
    4.2 m away (the column, 0.6 m wide, is no wall)."""
    why, result = _lap_in(HALL + COLUMN, ROUND_THE_COLUMN, ALL_OVER_THE_HALL, to_long_walls=True)
    assert why == "a 6 m circle without a new feature: heading for the nearest long wall"
    assert result.crossings == 1
