"""The random exploration of §3.3.4 shared by every method: follow the wall, wait for passers-by.

The baselines drive exactly as ``bim-init run`` explores (§4.3: "using the same wall following
based motion planning algorithm"), so distances compare like for like.
"""

from __future__ import annotations

from initcli.core.wall_following import MovingObstacleWait, ScanView, wall_follow
from initcli.drivers.base import SensorFrame
from initcli.session.config import SessionConfig, followed_side, wall_follow_params


class WallFollowingExplorer:
    """Velocity commands for random exploration, one control period at a time."""

    def __init__(self, config: SessionConfig):
        self.side = followed_side(config)
        self.params = wall_follow_params(config)
        self.waiting = MovingObstacleWait()

    def command(self, frame: SensorFrame) -> tuple[float, float]:
        if frame.scan is None:
            return 0.0, 0.0
        scan = ScanView.of(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
        if self.waiting.hold(frame.t, scan.front(), self.params.front_stop):
            return 0.0, 0.0
        return wall_follow(scan, self.side, self.params)
