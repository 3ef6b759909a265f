"""What one session found: the poses at each stage, how far it went, and its errors against truth."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Any

import numpy as np

from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.match.pipeline import DECIDED_BY_LIDAR, DECIDED_BY_PAPER
from initcli.verify.registration import DECIDED_BY_REGISTRATION

if TYPE_CHECKING:
    from initcli.config.session import LimitsSection
    from initcli.match.pipeline import Hypothesis, MatchReport

__all__ = [
    "CANNOT_LEAVE",
    "CoarseClaim",
    "DecidedBy",
    "MatchStep",
    "SHUT_IN",
    "SHUT_IN_ADVICE",
    "SessionResult",
    "ShutIn",
    "limit_reason",
]

# The reason of a simulated session refused at 0 m (sim.refuse_enclosed): the simulator knows its
# start lies in a space closed off from where the features face.
CANNOT_LEAVE = (
    "cannot leave: the start is in a space closed off by doors, hoardings or material "
    "(no way wide enough for the robot to the corridors, where the features face)"
)

SHUT_IN = "shut in"  # the reason of a session that stopped shut in (a stable word of summary.json)
SHUT_IN_ADVICE = "open a door or move the robot"


class DecidedBy(StrEnum):
    """What made a claim unique (summary.json's ``decided_by``)."""

    PAPER = DECIDED_BY_PAPER  # one place by the features alone (Algorithm 1)
    LIDAR = DECIDED_BY_LIDAR  # one of several hypotheses, picked by the lidar along the path
    REGISTRATION = DECIDED_BY_REGISTRATION  # the lidar submap alone


@dataclass
class MatchStep:
    """One matching step, for the report: time, features so far, hypotheses' current poses."""

    t: float  # s
    features: int
    verdict: str
    poses: list[tuple[float, float, float]]  # (x m, y m, yaw rad) in the BIM frame

    @classmethod
    def of(cls, t: float, report: MatchReport) -> MatchStep:
        """The step that gave ``report`` at ``t``."""
        return cls(t, len(report.features), report.verdict, [h.pose.as_tuple() for h in report.hypotheses])


@dataclass(frozen=True)
class CoarseClaim:
    """A unique match reported as the coarse result: its rectified pose (Eq. 17), the truth then
    (simulated sessions), and the distance and wall-clock seconds it took."""

    rectified_pose: Pose2D
    truth: Pose2D | None
    distance_m: float
    wall_seconds: float


@dataclass(frozen=True)
class ShutIn:
    """The robot went round the space it is in without a new feature and its local map has no
    opening left that it can pass: what it explored and saw (initcli.session.escapes)."""

    explored_m2: float  # the free area of its local map
    features: int  # features confirmed
    lap_m: float  # m of the last lap
    advice: str = SHUT_IN_ADVICE

    @property
    def message(self) -> str:
        """The line a person reads: ``shut in: explored 28 m2, saw 2 features; open a door ...``."""
        n = self.features
        return (
            f"{SHUT_IN}: explored {self.explored_m2:.0f} m2, saw {n} feature{'' if n == 1 else 's'};"
            f" {self.advice}"
        )


@dataclass
class SessionResult:
    success: bool
    reason: str
    storey: str | None
    pose: Pose2D | None = None
    covariance: np.ndarray | None = None
    coarse_pose: Pose2D | None = None
    rectified_pose: Pose2D | None = None
    features_detected: int = 0
    distance_coarse_m: float | None = None
    distance_total_m: float = 0.0
    duration_s: float = 0.0
    truth_pose: Pose2D | None = None
    truth_at_coarse: Pose2D | None = None
    matched_ids: list[str | None] = field(default_factory=list)
    transform: Pose2D | None = None  # odom -> BIM of the final estimate
    true_path: list[tuple[float, float, float]] = field(default_factory=list)
    odom_path: list[tuple[float, float, float]] = field(default_factory=list)
    features: list[ConfirmedFeature] = field(default_factory=list)
    match_steps: list[MatchStep] = field(default_factory=list)
    states: list[tuple[float, str]] = field(default_factory=list)
    active_explorations: int = 0
    loop_escapes: int = 0
    crossings: int = 0  # open floors crossed after a look (beyond the paper)
    fine_converged: bool | None = None
    recoveries: int = 0
    wall_seconds: float = 0.0
    wall_seconds_coarse: float | None = None  # wall-clock seconds until the unique match
    verifications: list[dict[str, Any]] = field(default_factory=list)  # every check, in order
    rejected: int = 0  # unique matches that failed verification
    # The first coarse claim: where the coarse-only method ends (the fields above describe the
    # last claim, which differs after a failed fine stage and a second claim).
    first_claim: CoarseClaim | None = None
    shut_in: ShutIn | None = None  # the session stopped shut in (reason SHUT_IN)
    decided_by: DecidedBy | None = None  # what made the last claim unique; None: no claim
    laps: int = 0  # laps without a new feature after which the robot headed for an opening

    def claimed(
        self,
        best: Hypothesis,
        truth: Pose2D | None,
        distance_m: float,
        wall_seconds: float,
        features: Sequence[ConfirmedFeature],
    ) -> None:
        """A coarse claim of hypothesis ``best`` (its rectified pose, Eq. 17) after ``distance_m`` of
        driving and ``wall_seconds``; ``features``: the ones matched (a drift window may leave old
        ones out)."""
        self.storey = best.storey
        self.coarse_pose = best.pose
        self.rectified_pose = best.reported_pose
        self.truth_at_coarse = truth
        self.distance_coarse_m = round(distance_m, 3)
        self.wall_seconds_coarse = wall_seconds
        if self.first_claim is None:
            self.first_claim = CoarseClaim(best.reported_pose, truth, self.distance_coarse_m, wall_seconds)
        self.matched_ids = list(best.matches)
        self.features = list(features)

    def initialised(
        self,
        pose: Pose2D,
        covariance: np.ndarray | None,
        odom: Pose2D,
        truth: Pose2D | None,
        t: float,
        distance_m: float,
    ) -> None:
        """The session ends initialised at ``pose`` (``covariance`` None: no fine tuning), the robot
        at ``odom`` in its odometry frame, at time ``t`` after ``distance_m`` of driving."""
        self.success = True
        if covariance is None:
            self.reason = "initialised (no fine tuning)"
        elif self.fine_converged:
            self.reason = "initialised"
        else:
            self.reason = (
                "initialised (fine tuning stopped at its distance limit above the covariance threshold)"
            )
        self.pose, self.covariance = pose, covariance
        self.transform = pose * odom.inverse()
        self.truth_pose = truth
        self.distance_total_m = round(distance_m, 3)
        self.duration_s = round(t, 2)

    def failed(
        self,
        reason: str,
        truth: Pose2D | None,
        t: float,
        distance_m: float,
        features: Sequence[ConfirmedFeature],
    ) -> None:
        """The session ends without a pose, for ``reason``, at time ``t`` after ``distance_m``."""
        self.success, self.reason = False, reason
        self.distance_total_m = distance_m
        self.duration_s = t
        self.truth_pose = truth
        self.features = list(features)

    def errors(self) -> tuple[dict[str, float | None], dict[str, float | None]]:
        """Translational (m) and rotational (deg) errors of the coarse, rectified and fine poses."""
        trans: dict[str, float | None] = {"coarse": None, "rectified": None, "fine": None}
        rot: dict[str, float | None] = {"coarse": None, "rectified": None, "fine": None}
        for key, pose, truth in (
            ("coarse", self.coarse_pose, self.truth_at_coarse),
            ("rectified", self.rectified_pose, self.truth_at_coarse),
            ("fine", self.pose if self.covariance is not None else None, self.truth_pose),
        ):
            if pose is not None and truth is not None:
                trans[key] = round(math.hypot(pose.x - truth.x, pose.y - truth.y), 4)
                rot[key] = round(math.degrees(abs(float(wrap_angle(pose.yaw - truth.yaw)))), 3)
        return trans, rot


def limit_reason(
    limits: LimitsSection,
    travel: float,
    t: float,
    features: int,
    hypotheses: int,
    storeys: Sequence[str] = (),
    earlier_fine_failure: str = "",
) -> str | None:
    """Why a session that drove ``travel`` m by its odometry (what the robot knows, not the true
    path) until session time ``t`` s is over its ``limits``, or None while it is within them."""
    max_distance, max_time = limits.max_distance, limits.max_time
    if travel > max_distance:
        left = f" on storeys {', '.join(storeys)}: the storey is not resolved" if len(storeys) > 1 else ""
        earlier = (
            f"; the fine stage of an earlier one failed: {earlier_fine_failure}"
            if earlier_fine_failure
            else ""
        )
        return (
            f"moved {max_distance:g} m without a unique match ({features} features, "
            f"{hypotheses} hypotheses{left}){earlier}"
        )
    if t > max_time:
        return f"no unique match within {max_time:g} s"
    return None
