"""Ways out of the wall follower's traps (beyond the paper): loops, shuttling, open floors.

Wall following circles an island of clutter or an open hall with no wall in reach (a *loop*), or
shuttles over the same few metres for minutes (a dead end behind a material stack, targets that
keep failing). Out of a loop the robot drives to the nearest unexplored opening the lidar has
seen (a frontier of :class:`~initcli.core.navigation.frontier.LocalMap`), else along the most open direction;
when shuttling it follows the other wall. A *lap* (:class:`~initcli.core.navigation.laps.LapWatch`: back where
it was after its path turned once round a room, a hall or a closed corridor section) that brought no
new feature sends it to an opening of the local map it can pass; with none left it is *shut in*,
and the session stops (:class:`~initcli.session.result.ShutIn`). A crossing drives across an open
floor to a wall the lidar sees (:func:`~initcli.core.navigation.bug_navigation.cross_floor`). While one of
them is under way it steers instead of the wall follower.

The settings are ``exploration.loops``, ``exploration.shuttles``, ``exploration.frontier`` and
``exploration.laps`` of the session config.
"""

from __future__ import annotations

import math

import numpy as np

from initcli.config.exploration import FrontierSettings, LapSettings, LoopSettings, ShuttleSettings, WallSide
from initcli.core.navigation.bug_navigation import (
    GAP_SPEED,
    BugNavigator,
    BugParams,
    FloorCrossing,
    RouteNavigator,
    cross_floor,
    crossing_to,
)
from initcli.core.navigation.confinement import ConfinementWatch
from initcli.core.navigation.feature_walls import toward_long_wall
from initcli.core.navigation.frontier import LocalMap
from initcli.core.navigation.laps import LapWatch
from initcli.core.navigation.wall_following import ScanView, WallFollowParams
from initcli.drivers.base import SensorFrame
from initcli.session.result import SessionResult, ShutIn

__all__ = ["Escapes", "LAP_ROUTE_PASS", "LAP_ROUTE_SPACING", "PATH_STRIDE", "open_point", "path_points"]

# A route after a lap leads through a doorway barely wider than the robot: waypoints close together,
# each passed closely, driven at GAP_SPEED with this slack plus this many seconds (turns on the spot).
LAP_ROUTE_SPACING = 0.5  # m between waypoints
LAP_ROUTE_PASS = 0.2  # m: an intermediate waypoint counts as passed this close
LAP_ROUTE_PREFER = 0.45  # m: closer than this to what is not known free costs more (mid-doorway)
LAP_ROUTE_SLACK = 1.5
# Shut in needs a lap round the space: its path encloses at least this share of the free area the
# local map holds (round a 5 x 6 m room at 0.7 m from the walls: 0.55; a 1.3 m circle in a hall: 0.05).
LAP_ENCLOSES = 0.2
# ... and a lap this short round little is round a column (0.3-0.6 m columns followed at 0.7 m:
# laps of 7-11 m in the LiNear car park), not a corridor loop that the lidar saw far beyond.
COLUMN_LAP_M = 12.0
LAP_ROUTE_EXTRA_S = 20.0
# Every this many odometry samples of the path is where the robot was, for exploration.long_walls
# (at 10 Hz and 0.4 m/s: every 0.4 m).
PATH_STRIDE = 10


def path_points(result: SessionResult) -> np.ndarray:
    """Where the robot was (odom x, y; K x 2): every PATH_STRIDE-th sample of the session's path."""
    return np.array(result.odom_path[::PATH_STRIDE], dtype=float).reshape(-1, 3)[:, :2]


def open_point(frame: SensorFrame, scan: ScanView | None, loops: LoopSettings) -> np.ndarray:
    """An odom point ``open_reach`` along the longest free beam (or ``open_short`` short of the
    obstacle it hit); ``blind_reach`` straight ahead with no scan."""
    if scan is None or len(scan.ranges) == 0:
        return frame.odom.apply(np.array([loops.blind_reach, 0.0]))
    i = int(np.argmax(scan.ranges))
    reach = min(loops.open_reach, float(scan.ranges[i]) - loops.open_short)
    return frame.odom.apply(reach * np.array([math.cos(scan.angles[i]), math.sin(scan.angles[i])]))


class Escapes:
    """The watches for loops and shuttling, the local map of what the lidar has seen, and the escape
    or crossing under way (counted in ``result``); ``long_walls``: ``exploration.long_walls``."""

    def __init__(
        self,
        loops: LoopSettings,
        shuttles: ShuttleSettings,
        frontier: FrontierSettings,
        laps: LapSettings,
        long_walls: bool,
        follow: WallFollowParams,
        result: SessionResult,
    ) -> None:
        self.settings = loops
        self.lap_settings = laps
        self.frontier = frontier
        self.follow = follow
        self.result = result
        self.loops = ConfinementWatch(loops.window, loops.length, loops.radius)
        self.shuttles = ConfinementWatch(shuttles.window, shuttles.length, shuttles.radius)
        self.local_map = LocalMap()  # what the lidar has seen, for frontier-guided loop escapes
        self.navigator: BugNavigator | RouteNavigator | None = None  # the escape or crossing
        self.until = -1.0  # s: when it ends
        lap = self.lap_settings
        self.laps = LapWatch(min_lap=lap.length, radius=lap.radius, turn=math.radians(lap.turn))
        self.lap_target: np.ndarray | None = None  # the opening the last lap sent the robot to
        self.to_long_walls = long_walls  # out of a circle round a column to a long wall

    def see(self, frame: SensorFrame, step: int) -> None:
        """Write every ``frontier.scan_every``-th scan into the local map (every ``beam_step``-th beam)."""
        if frame.scan is not None and step % self.frontier.scan_every == 0:
            s = frame.scan
            k = self.frontier.beam_step
            self.local_map.integrate(frame.odom, s.angles[::k], s.ranges[::k], s.range_max)

    def under_way(self, frame: SensorFrame) -> bool:
        """Does an escape or a crossing steer the robot now?"""
        return self.navigator is not None and frame.t < self.until

    def step(self, frame: SensorFrame, scan: ScanView) -> tuple[float, float]:
        """The command (v m/s, w rad/s) of the escape under way; it ends when it arrives."""
        assert self.navigator is not None
        v, w, arrived = self.navigator.step(frame.odom, scan)
        if arrived:
            self.navigator = None
        return v, w

    def cancel(self) -> None:
        """Drop the escape or crossing under way (the robot goes on from elsewhere)."""
        self.navigator = None

    def looping(self, frame: SensorFrame) -> bool:
        """Has the robot, with no escape under way, driven a long way in the last ``loops.window``
        seconds while staying in a small area?"""
        return frame.t >= self.until and self.loops.confined(frame.t, frame.odom)

    def shuttling(self, frame: SensorFrame) -> bool:
        """Has the robot shuttled over the same ground for ``shuttles.window`` seconds?"""
        return self.shuttles.confined(frame.t, frame.odom)

    def after_shuttling(self, frame: SensorFrame, side: int, exploring: bool) -> str:
        """The robot shuttled and follows the wall on ``side`` now (+1 left, -1 right); ``exploring``
        (random exploration, not active): head for the nearest opening the lidar has seen and not yet
        reached first, as out of a loop (shuttling in a corridor section a stack or a hoarding narrows).
        Returns why, for the log."""
        heading = exploring and self.head_for_frontier(frame)
        then = "heading for an unexplored opening, then " if heading else ""
        wall = WallSide.LEFT if side > 0 else WallSide.RIGHT
        return f"shuttling over the same ground; {then}following the {wall} wall"

    def out_of_loop(self, frame: SensorFrame, scan: ScanView | None) -> None:
        """Drive to the nearest unexplored opening the lidar has seen, else out along the most open
        direction (:func:`open_point`)."""
        if not self.head_for_frontier(frame):
            toward = open_point(frame, scan, self.settings)
            self.start(frame, BugNavigator(toward, BugParams(follow=self.follow)))

    def head_for_frontier(self, frame: SensorFrame) -> bool:
        """Drive to the nearest unexplored opening of the local map; False if there is none."""
        route = self.local_map.plan(frame.odom)
        if route:
            self.start(frame, RouteNavigator(route, BugParams(follow=self.follow)))
        return bool(route)

    def lap(self, frame: SensorFrame, travel: float, features: int) -> str | ShutIn | None:
        """Watch for a lap round the space the robot is in (``travel`` m of odometry so far,
        ``features`` confirmed): a lap that brought no new feature sends the robot to the nearest
        opening of its local map that it can pass (an opening an earlier lap sent it to and that it
        came round from is not chosen again while others are left), and returns why, for the log;
        with no opening it can pass on its map it returns :class:`ShutIn` (``laps.shut_in`` false:
        None). None while no such lap closed."""
        if not self.laps.add(travel, frame.odom.x, frame.odom.y, features) or self.under_way(frame):
            return None
        lap = self.laps.lap()
        if lap is None or features > lap.seen:
            return None
        self.laps.restart()
        if self.lap_target is not None:
            self.local_map.give_up(self.lap_target)
        circle = lap.enclosed < LAP_ENCLOSES * self.local_map.free_area()
        if circle and lap.length <= COLUMN_LAP_M and self.to_long_walls and frame.scan is not None:
            # Round a column on an open floor: its openings lead to the next column; the features
            # are on the walls (exploration.long_walls).
            s = frame.scan
            view = ScanView.of(s.angles, s.ranges, s.range_max)
            way = toward_long_wall(view, frame.odom.apply_inverse(path_points(self.result)))
            if way is not None and self.cross(frame, view, 1, way) is not None:
                return f"a {lap.length:.0f} m circle without a new feature: heading for the nearest long wall"
        # A doorway barely wider than the robot: the map's cells blur each jamb by up to a cell.
        clearance = self.follow.radius - self.local_map.params.resolution / 4
        route = self.local_map.plan(frame.odom, clearance, spacing=LAP_ROUTE_SPACING, prefer=LAP_ROUTE_PREFER)
        if not route and self.local_map.forget_failures():
            # Every opening it can pass was tried and it came round again: an opening it failed to
            # get through is still a way out (not shut in), tried again from here.
            route = self.local_map.plan(
                frame.odom, clearance, spacing=LAP_ROUTE_SPACING, prefer=LAP_ROUTE_PREFER
            )
        if route:
            self.lap_target = route[-1]
            squeeze = BugParams(follow=self.follow, squeeze=True)
            length = float(
                np.sum(np.hypot(*np.diff(np.vstack([[frame.odom.x, frame.odom.y], route]), axis=0).T))
            )
            seconds = max(self.settings.escape, LAP_ROUTE_SLACK * length / GAP_SPEED + LAP_ROUTE_EXTRA_S)
            self.start(frame, RouteNavigator(route, squeeze, pass_radius=LAP_ROUTE_PASS), seconds)
            self.result.laps += 1
            return f"a {lap.length:.0f} m lap without a new feature: heading for an unexplored opening"
        if not self.lap_settings.shut_in:
            return None
        if circle:
            # A circle on an open floor (the wall follower lost its wall), not a lap round the room:
            # the loop watch drives it out; shut in needs the lap round what the robot has seen.
            return f"a {lap.length:.0f} m circle without a new feature on an open floor"
        return ShutIn(round(self.local_map.free_area(), 1), features, round(lap.length, 1))

    def start(
        self, frame: SensorFrame, navigator: BugNavigator | RouteNavigator, seconds: float | None = None
    ) -> None:
        """Follow ``navigator`` for ``seconds`` (default ``loops.escape``) instead of the wall (a loop
        escape)."""
        self.navigator = navigator
        self.until = frame.t + (self.settings.escape if seconds is None else seconds)
        self.result.loop_escapes += 1

    def cross(
        self, frame: SensorFrame, scan: ScanView, side: int, way: tuple[float, float] | None = None
    ) -> FloorCrossing | None:
        """Drive across the open floor on the side away from the followed wall (``side``) to a wall
        the lidar sees (:func:`cross_floor`), or along ``way`` (bearing rad, reach m) when given; None
        when there is none to drive to."""
        crossing = (
            cross_floor(frame.odom, scan, side, self.follow)
            if way is None
            else crossing_to(frame.odom, *way, self.follow)
        )
        if crossing is None:
            return None
        self.navigator = crossing.navigator
        self.until = frame.t + crossing.seconds
        self.result.crossings += 1
        return crossing
