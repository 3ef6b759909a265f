"""Has the robot gone once round the space it is in? A lap of its own odometry path.

A wall follower in a room, a hall or a corridor section closed at both ends drives round it for
ever (§3.3.4's random exploration knows no way out): the room is larger than a loop
(:mod:`initcli.core.navigation.confinement`), so the robot's path is long but never small. What the robot
itself can know is that it came back to where it was after turning once round (the path's
direction changed by a full turn) and saw nothing new on the way: then the frontier of its local
map (:mod:`initcli.core.navigation.frontier`) tells whether there is a way on it can pass, or
whether it is shut
in. Samples are taken by distance travelled, so turning on the spot (a look round) adds no turn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from initcli.core.geometry.se2 import wrap_angle

__all__ = ["Lap", "LapWatch", "MAX_SAMPLES"]

MAX_SAMPLES = 1000  # samples kept (500 m at the default step): laps longer than that are not seen


@dataclass(frozen=True)
class Lap:
    """A lap closed at the newest sample: where it began (m of travel) and how long it was."""

    began: float  # m of travel at the sample the lap returned to
    length: float  # m
    turn: float  # rad the path's direction turned over the lap (signed)
    seen: int  # what was counted (features confirmed) when the lap began
    enclosed: float = 0.0  # m2 the lap's path encloses (shoelace formula)


@dataclass
class LapWatch:
    """The odometry path sampled every ``step`` m of travel, and the laps it closes: back within
    ``radius`` m of a point passed at least ``min_lap`` m earlier, the path's direction turned by at
    least ``turn`` radians since."""

    step: float = 0.5  # m of travel between samples
    min_lap: float = 6.0  # m: a lap is at least this long
    radius: float = 1.0  # m: back this close to where the lap began
    turn: float = math.radians(315.0)  # rad the path's direction must have turned
    travel: list[float] = field(default_factory=list)
    xy: list[tuple[float, float]] = field(default_factory=list)
    winding: list[float] = field(default_factory=list)  # rad: the direction's cumulative turn
    seen: list[int] = field(default_factory=list)  # features confirmed at each sample
    _heading: float | None = None

    def add(self, travel: float, x: float, y: float, seen: int = 0) -> bool:
        """Record the robot at ``(x, y)`` (odom) after ``travel`` m, having confirmed ``seen``
        features; True when a sample was taken."""
        if self.travel and travel - self.travel[-1] < self.step:
            return False
        if self.xy:
            px, py = self.xy[-1]
            if math.hypot(x - px, y - py) < 0.5 * self.step:
                return False  # odometry travel without displacement (turning on the spot)
            heading = math.atan2(y - py, x - px)
            turned = 0.0 if self._heading is None else float(wrap_angle(heading - self._heading))
            self._heading = heading
            self.winding.append(self.winding[-1] + turned)
        else:
            self.winding.append(0.0)
        self.travel.append(travel)
        self.xy.append((x, y))
        self.seen.append(seen)
        if len(self.xy) > MAX_SAMPLES:
            del self.travel[0], self.xy[0], self.winding[0], self.seen[0]
        return True

    def lap(self) -> Lap | None:
        """The shortest lap that the newest sample closes, or None."""
        if len(self.xy) < 3:
            return None
        n = len(self.xy) - 1
        x, y = self.xy[n]
        for i in range(n - 1, -1, -1):
            length = self.travel[n] - self.travel[i]
            if length < self.min_lap:
                continue
            turned = self.winding[n] - self.winding[i]
            px, py = self.xy[i]
            if abs(turned) >= self.turn and math.hypot(x - px, y - py) <= self.radius:
                return Lap(self.travel[i], length, turned, self.seen[i], self._enclosed(i, n))
        return None

    def _enclosed(self, i: int, n: int) -> float:
        """The area (m2) the path from sample ``i`` to sample ``n`` encloses, closed by a straight
        line back."""
        xs = [p[0] for p in self.xy[i : n + 1]]
        ys = [p[1] for p in self.xy[i : n + 1]]
        twice = sum(xs[k] * ys[k + 1] - xs[k + 1] * ys[k] for k in range(len(xs) - 1))
        twice += xs[-1] * ys[0] - xs[0] * ys[-1]
        return abs(twice) / 2.0

    def restart(self) -> None:
        """Forget the path: the next lap is counted from the newest sample on."""
        if self.xy:
            self.travel, self.xy, self.seen = self.travel[-1:], self.xy[-1:], self.seen[-1:]
            self.winding = [0.0]
