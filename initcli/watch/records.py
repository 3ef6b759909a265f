"""What ``bim-init watch`` decides: its states, one check of the localiser's pose, and the events
(``--json``: ``{"events": [{"t", "kind", "pose", "reason"}, ...]}``)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from initcli.core.geometry.se2 import Pose2D

__all__ = ["EventKind", "WatchCheck", "WatchEvent", "WatchState", "pose_dict"]


class WatchState(StrEnum):
    """Where the watch stands (``/bim_init/state``)."""

    WAITING = "waiting"  # no localiser pose, odometry or scan yet
    TRACKING = "tracking"  # the localiser's pose agrees with the model
    LOST = "lost"  # it does not; re-initialising from the scans since it went wrong


class EventKind(StrEnum):
    LOST = "lost"  # the localiser's pose is wrong
    RECOVERED = "recovered"  # a pose found again (``pose``), sent to the localiser
    SUSPECT = "suspect"  # the evidence passed the threshold, but the lidar's best place is the localiser's


def pose_dict(pose: Pose2D) -> dict[str, float]:
    return {"x": round(pose.x, 4), "y": round(pose.y, 4), "yaw": round(pose.yaw, 5)}


@dataclass(frozen=True)
class WatchEvent:
    t: float  # s, the robot's clock (the stamp of the scan that decided)
    kind: EventKind
    travel: float  # m of odometry travel since the watch began
    reason: str
    pose: Pose2D | None = None  # recovered: the robot's pose, map (site) frame
    storey: str | None = None

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"t": round(self.t, 6), "kind": str(self.kind), "travel": round(self.travel, 3)}
        if self.pose is not None:
            out["pose"] = pose_dict(self.pose)
        if self.storey is not None:
            out["storey"] = self.storey
        out["reason"] = self.reason
        return out


@dataclass(frozen=True)
class WatchCheck:
    """One check of the localiser's pose (the plot's and ``--json``'s ``checks``)."""

    t: float
    travel: float
    localiser: Pose2D  # the pose checked (map frame)
    fit: float  # share of the recent beam ends on mapped walls there
    through: float  # share of beams through mapped walls there
    off_free: float  # share of the robot's recent places off the map's free space there
    evidence: float  # the check's evidence of a wrong pose (initcli.core.watch.lost_test.wrongness)
    statistic: float  # the CUSUM after it
    state: WatchState

    def as_dict(self) -> dict[str, Any]:
        return {
            "t": round(self.t, 6),
            "travel": round(self.travel, 3),
            "localiser": pose_dict(self.localiser),
            "fit": round(self.fit, 4),
            "through": round(self.through, 4),
            "off_free": round(self.off_free, 4),
            "evidence": round(self.evidence, 4),
            "statistic": round(self.statistic, 4),
            "state": str(self.state),
        }
