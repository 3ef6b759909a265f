"""The random exploration of §3.3.4 shared by every method: follow the wall, wait for passers-by.

The baselines drive exactly as ``bim-init run`` explores (§4.3: "using the same wall following
based motion planning algorithm"), including its initial turn on the spot
(``exploration.initial_look``), so distances compare like for like.
"""

from __future__ import annotations

import math

from initcli.config import SessionConfig, followed_side, turn_in_place_speed, wall_follow_params
from initcli.core.geometry import wrap_angle
from initcli.core.wall_following import MovingObstacleWait, ScanView, wall_follow
from initcli.drivers.base import SensorFrame


class WallFollowingExplorer:
    """Velocity commands for random exploration, one control period at a time."""

    def __init__(self, config: SessionConfig):
        self.side = followed_side(config)
        self.params = wall_follow_params(config)
        self.waiting = MovingObstacleWait()
        self.look_speed = turn_in_place_speed(config)
        self.to_turn = 2 * math.pi if config.exploration.initial_look else 0.0
        self.last_yaw: float | None = None

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        if self.to_turn > 0:
            if self.last_yaw is not None:
                self.to_turn -= abs(float(wrap_angle(frame.odom.yaw - self.last_yaw)))
            self.last_yaw = frame.odom.yaw
            if self.to_turn > 0:
                return 0.0, self.look_speed
        if frame.scan is None:
            return 0.0, 0.0
        scan = ScanView.of(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
        if self.waiting.hold(frame.t, scan.front(), self.params.front_stop):
            return 0.0, 0.0
        return wall_follow(scan, self.side, self.params)
