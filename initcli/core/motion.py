"""The odometry motion model's decomposition of a move: (rot1, trans, rot2).

The motion between two poses as a turn toward the new position, a straight translation and a
final turn (probabilistic robotics' odometry model, as AMCL uses it). The simulated robot draws
its odometry noise on these three, and the particle filters (Eq. 18, AMCL) predict with them.
"""

from __future__ import annotations

import math

from initcli.core.geometry import Pose2D, wrap_angle

__all__ = ["apply_delta", "motion_delta"]


def motion_delta(a: Pose2D, b: Pose2D) -> tuple[float, float, float]:
    """The (rot1 rad, trans m, rot2 rad) decomposition of the motion from ``a`` to ``b``."""
    dx, dy = b.x - a.x, b.y - a.y
    trans = math.hypot(dx, dy)
    rot1 = float(wrap_angle(math.atan2(dy, dx) - a.yaw)) if trans > 1e-6 else 0.0
    # Driving backwards: express as a backward translation rather than a half turn.
    if abs(rot1) > math.pi / 2:
        rot1 = float(wrap_angle(rot1 - math.pi))
        trans = -trans
    rot2 = float(wrap_angle(b.yaw - a.yaw - rot1))
    return rot1, trans, rot2


def apply_delta(pose: Pose2D, rot1: float, trans: float, rot2: float) -> Pose2D:
    """``pose`` moved by (rot1 rad, trans m, rot2 rad): the inverse of :func:`motion_delta`."""
    heading = pose.yaw + rot1
    return Pose2D(
        pose.x + trans * math.cos(heading),
        pose.y + trans * math.sin(heading),
        float(wrap_angle(heading + rot2)),
    )
