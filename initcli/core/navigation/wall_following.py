"""Wall following on a 2D laser scan (§3.3.4 random exploration, §3.3.3 obstacle avoidance).

The controller tracks the nearest obstacle point on the followed side: it keeps that point at
the desired distance and straight abeam (90 degrees). With the left wall followed this turns
right at an inner corner (the nearest point moves ahead) and left around an outer corner (the
corner becomes the nearest point and drifts behind), as the paper's random exploration does.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from initcli.core.geometry.se2 import wrap_angle

__all__ = [
    "BEAM_CACHE_SIZE",
    "CROSS_BEARINGS",
    "CROSS_HALF_WIDTH",
    "CROSS_REACH",
    "CROSS_SHORT",
    "CROSS_WALL_M",
    "MovingObstacleWait",
    "OPEN_SIDE_M",
    "ScanView",
    "WALL_GAP_M",
    "WallFollowParams",
    "across_the_floor",
    "open_beside",
    "wall_ahead",
    "wall_follow",
    "wall_width",
]


@dataclass(frozen=True)
class WallFollowParams:
    distance: float = 0.7  # m kept to the followed wall
    speed: float = 0.5  # m/s cruise
    max_turn: float = 1.0  # rad/s
    front_stop: float = 0.6  # m: closer than this ahead -> turn in place away from the wall
    slow_down: float = 1.2  # m: speed falls off linearly inside this distance ahead
    k_distance: float = 1.5
    k_angle: float = 1.8
    lost: float = 2.0  # m: no wall point this close on the side -> arc toward it
    radius: float = 0.3  # m: the robot's footprint radius (the width of a way it can pass)


BEAM_CACHE_SIZE = 8  # beam layouts (a lidar's angles) whose directions ScanView keeps
OPEN_SIDE_M = 3.0  # m: nothing nearer on the side away from the followed wall is open space
CROSS_BEARINGS = (90, 75, 105, 60, 120, 45, 135)  # degrees off the heading a crossing may take ...
CROSS_REACH = 15.0  # m: ... driving at most this far ...
CROSS_HALF_WIDTH = 0.8  # m: ... along a way this wide either side clear of anything the lidar hit ...
CROSS_SHORT = 1.5  # m: ... and stopping this much short of what the lidar hit across the floor ...
CROSS_WALL_M = 2.0  # m: ... at a wall at least this wide (wall_width) ...
WALL_GAP_M = 0.5  # m: lidar end points this close to their neighbour's lie on one wall


@dataclass(frozen=True)
class ScanView:
    """Valid beams of a scan in the robot frame (``cos``/``sin`` of the angles when known)."""

    angles: np.ndarray
    ranges: np.ndarray
    cos: np.ndarray | None = None
    sin: np.ndarray | None = None

    @staticmethod
    def of(angles: np.ndarray, ranges: np.ndarray, max_range: float) -> ScanView:
        ok = np.isfinite(ranges) & (ranges > 0.05) & (ranges < max_range - 1e-6)
        wrapped, cos, sin = _beam_directions(np.asarray(angles, dtype=float))
        return ScanView(wrapped[ok], ranges[ok], cos[ok], sin[ok])

    def sector_min(self, lo: float, hi: float, default: float = math.inf) -> float:
        mask = (self.angles >= lo) & (self.angles <= hi)
        return float(self.ranges[mask].min()) if mask.any() else default

    @cached_property
    def xy(self) -> tuple[np.ndarray, np.ndarray]:
        """The beam end points in the robot frame (the wall follower asks for the front twice)."""
        cos = np.cos(self.angles) if self.cos is None else self.cos
        sin = np.sin(self.angles) if self.sin is None else self.sin
        return self.ranges * cos, self.ranges * sin

    def front(self, half_width: float = 0.35) -> float:
        """Distance ahead within a corridor of ``half_width`` metres (robot width + margin)."""
        return self.clear_along(0.0, half_width)

    def clear_along(self, bearing: float, half_width: float = 0.35) -> float:
        """Free distance along ``bearing`` (rad, robot frame) within a corridor of ``half_width``
        metres; inf when nothing the lidar hit is in that corridor."""
        along, mask = self._in_way(bearing, half_width)
        return float(along[mask].min()) if mask.any() else math.inf

    def way_along(self, bearing: float, half_width: float = 0.35) -> tuple[float, int]:
        """:meth:`clear_along` and the beam whose end point bounds it (inf and -1 when none does)."""
        along, mask = self._in_way(bearing, half_width)
        if not mask.any():
            return math.inf, -1
        hit = int(np.argmin(np.where(mask, along, np.inf)))
        return float(along[hit]), hit

    def _in_way(self, bearing: float, half_width: float) -> tuple[np.ndarray, np.ndarray]:
        """Each beam end point's distance along ``bearing`` (rad, robot frame), and which lie ahead
        within ``half_width`` m of that line."""
        x, y = self.xy
        if bearing != 0.0:
            c, s = math.cos(bearing), math.sin(bearing)
            x, y = c * x + s * y, -s * x + c * y
        return x, (x > 0) & (np.abs(y) <= half_width)


_BEAMS: OrderedDict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] = OrderedDict()


def _beam_directions(angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The angles wrapped to [-pi, pi) and their cosines and sines, kept per beam layout: a lidar
    sends the same angles with every scan, and each scan is seen by the wall follower."""
    key = angles.tobytes()
    found = _BEAMS.get(key)
    if found is None:
        wrapped = np.asarray(wrap_angle(angles), dtype=float)
        found = (wrapped, np.cos(wrapped), np.sin(wrapped))
        _BEAMS[key] = found
        if len(_BEAMS) > BEAM_CACHE_SIZE:
            _BEAMS.popitem(last=False)
    return found


def open_beside(scan: ScanView, side: int) -> bool:
    """Nothing within OPEN_SIDE_M across from the followed wall (``side`` +1 left, -1 right),
    30-150 degrees off the heading: a hall, a car park, an open-plan office, not a corridor."""
    lo, hi = sorted((-side * math.radians(30.0), -side * math.radians(150.0)))
    return scan.sector_min(lo, hi) >= OPEN_SIDE_M


def across_the_floor(scan: ScanView, side: int) -> tuple[float, float] | None:
    """Where to cross an open floor (beyond the paper): (bearing rad, reach m) toward a wall across
    it, of CROSS_BEARINGS off the heading toward the side away from the followed wall (``side`` +1
    left, -1 right): the way that gets farthest from the followed wall, square across first among
    equals; ``reach`` stops CROSS_SHORT short of the wall. A way counts only when the lidar hit a
    wall there within CROSS_REACH + CROSS_SHORT (:func:`wall_width` CROSS_WALL_M or more: not a
    column nor a row of them, not the void of a floor wider than the lidar sees; a beam with no
    return is not in the scan), and when that wall stands more than OPEN_SIDE_M out from the
    robot's line of travel. None when no way does. In an open-plan office the
    robot that follows the façade sees the doors of the rooms in the middle only from across."""
    best: tuple[float, float, float] | None = None  # (progress away from the wall, bearing, clear)
    for degrees in CROSS_BEARINGS:
        bearing = -side * math.radians(degrees)
        ahead = wall_ahead(scan, bearing)
        if ahead is None:
            continue
        clear, hit = ahead
        progress = clear * math.sin(math.radians(degrees))
        if progress <= OPEN_SIDE_M or wall_width(scan, hit) < CROSS_WALL_M:
            continue
        if best is None or progress > best[0] + 1e-6:
            best = (progress, bearing, clear)
    if best is None:
        return None
    return best[1], best[2] - CROSS_SHORT


def wall_ahead(scan: ScanView, bearing: float) -> tuple[float, int] | None:
    """(clear m, beam) of a way across the floor along ``bearing`` (rad, robot frame): clear
    CROSS_HALF_WIDTH m either side as far as a wall the lidar hit (that beam) within CROSS_REACH +
    CROSS_SHORT; None when the lidar hit nothing there (a beam with no return is not in the scan) or
    hit it farther."""
    clear, hit = scan.way_along(bearing, CROSS_HALF_WIDTH)
    if hit < 0 or clear > CROSS_REACH + CROSS_SHORT:
        return None
    return clear, hit


def wall_width(scan: ScanView, hit: int) -> float:
    """How wide the wall the lidar hit with beam ``hit`` is (m): the span of the run of beams on
    either side whose end points lie within WALL_GAP_M of their neighbour's (the scan's beams in
    angle order, as a lidar sends them)."""
    x, y = scan.xy
    n = len(x)
    ends = []
    for step in (-1, 1):
        k = hit
        while 0 <= k + step < n and math.hypot(x[k + step] - x[k], y[k + step] - y[k]) <= WALL_GAP_M:
            k += step
        ends.append(k)
    return math.hypot(x[ends[1]] - x[ends[0]], y[ends[1]] - y[ends[0]])


def wall_follow(scan: ScanView, side: int, p: WallFollowParams) -> tuple[float, float]:
    """Velocity command (v, w) that follows the wall on ``side`` (+1 left, -1 right)."""
    front = scan.front()
    if front < p.front_stop:
        return 0.0, -side * p.max_turn
    phi = side * scan.angles  # bearing measured toward the followed side
    mask = (phi > -math.radians(20)) & (phi < math.radians(170))
    speed = p.speed * min(max((front - p.front_stop) / max(p.slow_down - p.front_stop, 1e-6), 0.25), 1.0)
    if not mask.any() or scan.ranges[mask].min() > p.lost:
        # Lost the wall (outer corner or open space): arc toward the followed side.
        return speed * 0.6, side * min(p.max_turn, 0.6 * speed / max(p.distance, 0.1))
    i = int(np.argmin(np.where(mask, scan.ranges, np.inf)))
    d, bearing = float(scan.ranges[i]), float(phi[i])
    # A gap narrower than twice the wall distance (a stack against one wall, a door jamb): keep to
    # its middle, or the robot is pushed into the far side and turns back.
    across = (phi < -math.radians(60)) & (phi > -math.radians(120))
    distance = p.distance
    if across.any():
        distance = min(distance, 0.5 * (d + float(scan.ranges[across].min())))
    turn = p.k_angle * (bearing - math.pi / 2) + p.k_distance * (d - distance)
    w = min(max(side * turn, -p.max_turn), p.max_turn)
    v = speed * max(0.3, 1.0 - abs(w) / (2 * p.max_turn))
    return v, w


@dataclass
class MovingObstacleWait:
    """Stop for people: when something blocks the way, watch it for a moment before turning away.

    A wall ahead keeps its distance while the robot stands still; a worker walking by does not.
    The robot waits while the distance ahead keeps changing (up to ``max_wait`` seconds).
    """

    watch: float = 2.0  # s standing still to tell a wall from a person (who may step aside)
    max_wait: float = 6.0  # s
    moving: float = 0.04  # m change of the distance ahead that counts as motion
    since: float | None = None
    first: float = 0.0

    def hold(self, t: float, front: float, stop: float) -> bool:
        """True while the robot should stand still and wait."""
        if front >= stop:
            self.since = None
            return False
        if self.since is None:
            self.since, self.first = t, front
            return True
        waited = t - self.since
        if waited < self.watch:
            return True
        if abs(front - self.first) > self.moving and waited < self.max_wait:
            return True
        return False
