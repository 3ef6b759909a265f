"""The ``watch:`` section of the session config (``bim-init watch``): the lost test's settings
(:class:`initcli.core.watch.params.WatchParams`, beside its algorithm) with the watch's own added:
which topic holds the localiser's pose and whether the robot may drive to re-initialise."""

from __future__ import annotations

from dataclasses import dataclass

from bimkit.settings import setting
from initcli.core.watch.params import WatchParams

__all__ = ["AMCL_POSE_TOPIC", "POSE_FROM_TF", "WatchSection"]

AMCL_POSE_TOPIC = "/amcl_pose"  # AMCL's estimate: what the watch checks and the delivery confirms on
POSE_FROM_TF = "tf"  # the localiser's pose from /tf map -> odom instead of a topic


@dataclass
class WatchSection(WatchParams):
    pose_topic: str = setting(
        AMCL_POSE_TOPIC,
        f"the localiser's pose: a geometry_msgs/PoseWithCovarianceStamped topic, or {POSE_FROM_TF}"
        " (map -> base_link from /tf)",
    )
    drive: bool = setting(
        False,
        "when lost, drive as a session explores to gather scans for the re-initialisation (false: wait"
        " for the robot's own motion)",
    )
