"""The random exploration of §3.3.4 shared by every method: follow the wall, wait for passers-by.

The baselines drive exactly as ``bim-init run`` explores (§4.3: "using the same wall following
based motion planning algorithm"), including its initial turn on the spot
(``exploration.initial_look``), its looks on open floors (``exploration.look_every`` m of travel
along a wall with open space beside it; with no features to count, every that many metres) and its
drive across the open floor after every ``exploration.cross_after`` such looks, so distances
compare like for like.

Their drive does not depend on what they sense (the commands come from the scans alone), so
several baselines started from the same simulated setup drive the same path:
:func:`drive_attempts` drives it once and hands every frame to each attempt still running
(``bim-init eval`` runs AMCL and the markers that way; each attempt's outcome is the one it
would have had alone).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from typing import Protocol

from initcli.baselines.outcome import LocalisationOutcome
from initcli.config import SessionConfig, followed_side, turn_in_place_speed, wall_follow_params
from initcli.core.geometry.se2 import wrap_angle
from initcli.core.navigation.bug_navigation import BugNavigator, cross_floor
from initcli.core.navigation.wall_following import MovingObstacleWait, ScanView, open_beside, wall_follow
from initcli.drivers.base import RobotDriver, SensorFrame

__all__ = ["BaselineAttempt", "WallFollowingExplorer", "drive_attempts", "limit_passed"]


class WallFollowingExplorer:
    """Velocity commands for random exploration, one control period at a time."""

    def __init__(self, config: SessionConfig):
        self.side = followed_side(config)
        self.params = wall_follow_params(config)
        self.waiting = MovingObstacleWait()
        self.look_speed = turn_in_place_speed(config)
        self.to_turn = 2 * math.pi if config.exploration.initial_look else 0.0
        self.last_yaw: float | None = None
        self.look_every = config.exploration.look_every
        self.since_look = 0.0  # m of odometry travel since the last look (less a crossing's reach)
        self.last_xy: tuple[float, float] | None = None
        self.cross_after = config.exploration.cross_after
        self.looks = 0  # looks on an open floor since the last crossing
        self.looking = False  # a look on an open floor after which to cross is under way
        self.crossing: BugNavigator | None = None
        self.crossing_until = -1.0  # s

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        if self.to_turn > 0:
            if self.last_yaw is not None:
                self.to_turn -= abs(float(wrap_angle(frame.odom.yaw - self.last_yaw)))
            self.last_yaw = frame.odom.yaw
            if self.to_turn > 0:
                return 0.0, self.look_speed
        xy = (frame.odom.x, frame.odom.y)
        if self.last_xy is not None:
            self.since_look += math.hypot(xy[0] - self.last_xy[0], xy[1] - self.last_xy[1])
        self.last_xy = xy
        if frame.scan is None:
            return 0.0, 0.0
        scan = ScanView.of(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
        if self.looking:  # the look just ended: across the floor, as the session does
            self.looking = False
            crossing = cross_floor(frame.odom, scan, self.side, self.params)
            if crossing is not None:
                self.crossing, self.crossing_until = crossing.navigator, frame.t + crossing.seconds
                self.since_look, self.looks = -crossing.reach, 0
        if self.crossing is not None and frame.t < self.crossing_until:
            v, w, arrived = self.crossing.step(frame.odom, scan)
            if arrived:
                self.crossing = None
            return v, w
        if self.waiting.hold(frame.t, scan.front(), self.params.front_stop):
            return 0.0, 0.0
        if 0 < self.look_every <= self.since_look and open_beside(scan, self.side):
            self.since_look, self.to_turn, self.last_yaw = 0.0, 2 * math.pi, frame.odom.yaw
            self.looks += 1
            self.looking = 0 < self.cross_after <= self.looks
            return 0.0, self.look_speed
        return wall_follow(scan, self.side, self.params)


def limit_passed(config: SessionConfig, distance: float, t: float) -> str | None:
    """The session limit a baseline has passed ("150 m", "1200 s"), None while within both."""
    limits = config.limits
    if distance > limits.max_distance:
        return f"{limits.max_distance:g} m"
    if t > limits.max_time:
        return f"{limits.max_time:g} s"
    return None


class BaselineAttempt(Protocol):
    """One baseline localising along the shared drive."""

    def start(self, frame: SensorFrame) -> LocalisationOutcome | None:
        """The first frame, before any motion; an outcome ends the attempt."""
        ...

    def observe(self, frame: SensorFrame, step: int) -> LocalisationOutcome | None:
        """The frame after control period ``step`` (its limits checked here, in the attempt's own
        order); an outcome ends the attempt."""
        ...


def drive_attempts(
    config: SessionConfig, driver: RobotDriver, attempts: Sequence[BaselineAttempt]
) -> list[LocalisationOutcome]:
    """Drive one wall-following exploration until every attempt has an outcome (in their order);
    each outcome's ``wall_seconds`` is the time from the start of the drive to its end."""
    started = time.perf_counter()
    explorer = WallFollowingExplorer(config)
    outcomes: dict[int, LocalisationOutcome] = {}

    def finish(i: int, outcome: LocalisationOutcome | None) -> None:
        if outcome is not None:
            outcomes[i] = dataclasses.replace(outcome, wall_seconds=round(time.perf_counter() - started, 3))

    frame = driver.start()
    for i, attempt in enumerate(attempts):
        finish(i, attempt.start(frame))
    step = 0
    while len(outcomes) < len(attempts):
        v, w = explorer.command(frame)
        frame = driver.step(v, w)
        step += 1
        for i, attempt in enumerate(attempts):
            if i not in outcomes:
                finish(i, attempt.observe(frame, step))
    return [outcomes[i] for i in range(len(attempts))]
