"""Is the robot going round in circles? A path long in distance but small in extent.

Random exploration by wall following (§3.3.4) can circle an island of clutter or shuttle in a
dead end for ever; the session watches its recent odometry path for that and breaks out.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from initcli.core.geometry.se2 import Pose2D

__all__ = ["CHECK_EVERY_S", "ConfinementWatch", "FULL_WINDOW", "confined"]

CHECK_EVERY_S = 1.0  # s between two checks of a ConfinementWatch
FULL_WINDOW = 0.9  # fraction of the window the trace must span before it is judged


@dataclass
class ConfinementWatch:
    """:func:`confined` once a second over the robot's recent path (a loop round clutter,
    shuttling in a dead end); the trace starts afresh after each detection."""

    window_s: float  # s of path checked
    length: float  # m: a path longer than this over the window ...
    radius: float  # m: ... staying this close to its centre is confined
    trace: list[tuple[float, float, float]] = field(default_factory=list)  # (t s, x m, y m)
    checked: float = -1.0  # s: time of the last check

    def confined(self, t: float, odom: Pose2D) -> bool:
        if t - self.checked < CHECK_EVERY_S:
            return False
        self.checked = t
        if confined(self.trace, t, odom, self.window_s, self.length, self.radius):
            self.trace.clear()
            return True
        return False


def confined(
    trace: list[tuple[float, float, float]],
    t: float,
    odom: Pose2D,
    window_s: float,
    length: float,
    radius: float,
) -> bool:
    """Append the odom position at time ``t`` (s) to ``trace`` (kept ``window_s`` long) and tell
    whether the path over a full window is longer than ``length`` (m) yet stays within ``radius``
    (m) of its centre."""
    trace.append((t, odom.x, odom.y))
    while trace and trace[0][0] < t - window_s:
        trace.pop(0)
    if len(trace) < 2 or trace[-1][0] - trace[0][0] < FULL_WINDOW * window_s:
        return False
    xy = np.array([(x, y) for _, x, y in trace])
    travelled = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    spread = float(np.hypot(*(xy - xy.mean(axis=0)).T).max())
    return travelled > length and spread < radius
