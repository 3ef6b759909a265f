"""BIM-based active exploration: drive to a target with the modified bug algorithm (§3.3.3).

Turn toward the target (Eq. 15-16) and drive straight; when an obstacle blocks the way, follow
its wall on the side that keeps the target closest; leave the wall when the target is in line of
sight and closer than where the wall was met. Following the wall the wrong way round (the
target falling behind by more than ``give_up_margin``) turns back to follow it on the other side;
if that side leads away too, the robot heads straight for the target again. When the straight way
is blocked but a way as wide as the robot leads within ``GAP_SEARCH`` of it as far as the target (a
doorway, a gap between stacks; beyond the paper), the robot steers through that gap instead: a wall
follower cannot enter a doorway barely wider than itself. A route planned through a doorway on the
robot's own map (``BugParams.squeeze``) is driven closely: the robot turns on the spot toward each
near waypoint and drives while a way ``SQUEEZE_MARGIN`` wider than itself is clear that far.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.navigation.wall_following import ScanView, WallFollowParams, across_the_floor, wall_follow

__all__ = [
    "BugNavigator",
    "BugParams",
    "CROSSING_EXTRA_S",
    "CROSSING_SLACK",
    "FloorCrossing",
    "GAP_MARGIN",
    "GAP_REACH",
    "GAP_SEARCH",
    "GAP_SPEED",
    "GAP_STEP",
    "RouteNavigator",
    "SQUEEZE_LOOK",
    "SQUEEZE_SEARCH",
    "SQUEEZE_MARGIN",
    "around_side",
    "cross_floor",
    "crossing_to",
    "gap_bearing",
]

CROSSING_SLACK = 1.5  # a crossing may take this many times its drive at cruise speed ...
CROSSING_EXTRA_S = 5.0  # s ... plus this (turning toward it); then wall following resumes there
GAP_SEARCH = math.radians(35.0)  # a gap is looked for this far either side of the target's bearing ...
GAP_STEP = math.radians(2.0)  # ... at this step ...
GAP_REACH = 3.0  # m: ... leading as far as the target, or this far when it is farther
GAP_MARGIN = 0.05  # m beyond the robot's radius either side of the way through a gap
GAP_SPEED = 0.2  # m/s through a gap
SQUEEZE_MARGIN = 0.03  # m beyond the robot's radius either side of a squeezed route's way ...
SQUEEZE_LOOK = 0.4  # m ... clear at least this far ahead (or to the waypoint) ...
SQUEEZE_SEARCH = math.radians(80.0)  # ... along a bearing this close to the waypoint's (odometry drifts)


@dataclass(frozen=True)
class BugParams:
    arrive: float = 0.5  # m: target reached
    yaw_tolerance: float = math.radians(20)  # turn in place above this heading error
    k_yaw: float = 1.5
    follow: WallFollowParams = field(default_factory=WallFollowParams)
    give_up_margin: float = 1.5  # m farther from the target than where the wall was met
    squeeze: bool = False  # a route through a narrow way on the robot's own map: drive it closely


@dataclass
class BugNavigator:
    """Small state machine: ``go`` straight to the target, or ``follow`` a wall around an obstacle."""

    target: np.ndarray  # (x, y) in the odom frame
    params: BugParams = field(default_factory=BugParams)
    mode: str = "go"
    side: int = 1
    hit_distance: float = math.inf
    give_up_at: float = math.inf
    flipped: bool = False

    def step(self, pose: Pose2D, scan: ScanView) -> tuple[float, float, bool]:
        """(v, w, arrived)."""
        p = self.params
        dx, dy = float(self.target[0] - pose.x), float(self.target[1] - pose.y)
        distance = math.hypot(dx, dy)
        if distance < p.arrive:
            return 0.0, 0.0, True
        yaw_d = math.atan2(dy, dx)  # Eq. 15
        d_yaw = float(wrap_angle(yaw_d - pose.yaw))  # Eq. 16
        fp = p.follow
        if p.squeeze and self.mode == "go":
            # Turning on the spot never hits anything; then drive while the narrow way is clear.
            if abs(d_yaw) > p.yaw_tolerance:
                return 0.0, math.copysign(fp.max_turn * min(1.0, abs(d_yaw) / 0.6 + 0.3), d_yaw), False
            # Blocked: the nearest bearing (within GAP_SEARCH) that is clear that far (a jamb in the way).
            way = _clear_bearing(
                scan, d_yaw, fp.radius + SQUEEZE_MARGIN, min(distance, SQUEEZE_LOOK), SQUEEZE_SEARCH
            )
            if way is not None:
                if abs(way) > p.yaw_tolerance:
                    return 0.0, math.copysign(fp.max_turn * min(1.0, abs(way) / 0.6 + 0.3), way), False
                return (
                    min(GAP_SPEED, fp.speed),
                    float(np.clip(p.k_yaw * way, -fp.max_turn, fp.max_turn)),
                    False,
                )
        if self.mode == "follow":
            clear = scan.sector_min(d_yaw - 0.15, d_yaw + 0.15, default=math.inf)
            if distance < self.hit_distance - 0.3 and clear > min(distance, 3.0):
                self.mode = "go"
            elif distance > self.give_up_at:
                # Going round the wrong way (e.g. back along a corridor): try the other side once.
                if self.flipped:
                    self.mode, self.flipped = "go", False
                else:
                    self.side, self.flipped = -self.side, True
                    self.give_up_at = distance + p.give_up_margin
                    v, w = wall_follow(scan, self.side, fp)
                    return v, w, False
            else:
                v, w = wall_follow(scan, self.side, fp)
                return v, w, False
        gap = gap_bearing(scan, d_yaw, distance, fp.radius + GAP_MARGIN)
        if gap is not None:
            if abs(gap) > p.yaw_tolerance:
                return 0.0, math.copysign(fp.max_turn * min(1.0, abs(gap) / 0.6 + 0.3), gap), False
            return min(GAP_SPEED, fp.speed), float(np.clip(p.k_yaw * gap, -fp.max_turn, fp.max_turn)), False
        if scan.front() < fp.front_stop + 0.1 and abs(d_yaw) < math.pi / 2 and scan.front() < distance:
            self.mode = "follow"
            self.side = around_side(scan, d_yaw)
            self.hit_distance = distance
            self.give_up_at = distance + p.give_up_margin
            self.flipped = False
            v, w = wall_follow(scan, self.side, fp)
            return v, w, False
        if abs(d_yaw) > p.yaw_tolerance:
            return 0.0, math.copysign(fp.max_turn * min(1.0, abs(d_yaw) / 0.6 + 0.3), d_yaw), False
        speed = fp.speed * float(
            np.clip((scan.front() - fp.front_stop) / (fp.slow_down - fp.front_stop), 0.3, 1.0)
        )
        speed = min(speed, max(0.15, distance))
        return speed, float(np.clip(p.k_yaw * d_yaw, -fp.max_turn, fp.max_turn)), False


@dataclass
class RouteNavigator:
    """Follow waypoints (odom frame) one after the other with the bug navigator."""

    waypoints: list[np.ndarray]
    params: BugParams = field(default_factory=BugParams)
    pass_radius: float = 0.8  # m: an intermediate waypoint counts as passed this close
    current: BugNavigator | None = None

    def step(self, pose: Pose2D, scan: ScanView) -> tuple[float, float, bool]:
        while self.waypoints:
            last = len(self.waypoints) == 1
            if self.current is None:
                arrive = self.params.arrive if last else self.pass_radius
                self.current = BugNavigator(
                    self.waypoints[0],
                    dataclasses.replace(self.params, arrive=arrive),
                )
            v, w, arrived = self.current.step(pose, scan)
            if not arrived:
                return v, w, False
            self.waypoints.pop(0)
            self.current = None
        return 0.0, 0.0, True


def gap_bearing(scan: ScanView, d_yaw: float, distance: float, half_width: float) -> float | None:
    """The bearing (rad, robot frame) of a way ``half_width`` m either side clear as far as the target
    (``distance`` m at bearing ``d_yaw``; at most GAP_REACH) when the straight way is not; the one
    nearest the target's bearing within GAP_SEARCH. None when the straight way is clear (the bug
    navigator drives it) or no such way leads on."""
    need = min(distance, GAP_REACH)
    if scan.clear_along(d_yaw, half_width) >= need:
        return None
    return _clear_bearing(scan, d_yaw, half_width, need)


def _clear_bearing(
    scan: ScanView, d_yaw: float, half_width: float, need: float, search: float = GAP_SEARCH
) -> float | None:
    """The bearing nearest ``d_yaw`` (``d_yaw`` itself first, then GAP_STEP either side, within
    ``search``) along which a way ``half_width`` m either side is clear for ``need`` m; None: none is."""
    for k in range(int(search / GAP_STEP) + 1):
        for sign in (1.0, -1.0) if k else (1.0,):
            bearing = float(wrap_angle(d_yaw + sign * k * GAP_STEP))
            if scan.clear_along(bearing, half_width) >= need:
                return bearing
    return None


def around_side(scan: ScanView, d_yaw: float, margin: float = 0.3) -> int:
    """Which way round a blocking obstacle: +1 keeps it on the left (pass on the right), -1 on the
    right. The side with clearly more room wins (a material stack against one corridor wall);
    otherwise the side of the target."""
    left = scan.sector_min(0.2, 1.4, default=math.inf)
    right = scan.sector_min(-1.4, -0.2, default=math.inf)
    if abs(min(left, 5.0) - min(right, 5.0)) > margin:
        return 1 if right > left else -1
    return 1 if d_yaw <= 0 else -1  # target to the right: keep the obstacle on the left


@dataclass(frozen=True)
class FloorCrossing:
    """A drive across an open floor after a look there (beyond the paper, :func:`across_the_floor`)."""

    navigator: BugNavigator
    seconds: float  # allowed before wall following resumes wherever the robot is
    reach: float  # m


def cross_floor(pose: Pose2D, scan: ScanView, side: int, follow: WallFollowParams) -> FloorCrossing | None:
    """The crossing of the open floor beside the followed wall (``side``) from ``pose`` (odom);
    None when that side is not open."""
    across = across_the_floor(scan, side)
    if across is None:
        return None
    return crossing_to(pose, *across, follow)


def crossing_to(pose: Pose2D, bearing: float, reach: float, follow: WallFollowParams) -> FloorCrossing:
    """The drive from ``pose`` (odom) ``reach`` m along ``bearing`` (rad, robot frame) across a floor."""
    toward = pose.apply(reach * np.array([math.cos(bearing), math.sin(bearing)]))
    seconds = CROSSING_SLACK * reach / max(follow.speed, 1e-6) + CROSSING_EXTRA_S
    return FloorCrossing(BugNavigator(toward, BugParams(follow=follow)), seconds, reach)
