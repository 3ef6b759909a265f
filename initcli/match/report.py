"""What ``bim-init match`` finds: the :class:`MatchReport` record, its :class:`Hypothesis` rows and, when
a lidar registration decided the verdict, its :class:`RegistrationRecord`.

The report holds the verdict as its line (``verdict``, the console's last line) and its outcome
(``outcome``, a :class:`~initcli.core.hypotheses.ranking.Verdict`), set together by
:meth:`MatchReport.decide`; the command maps the outcome to its exit code
(``initcli.cli.exit_codes``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bimtools.site.load import Site
from initcli.config.matching import MatchOptions
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.ranking import Verdict, distinct_places, one_place, verdict_text
from initcli.io.detection_log import FeatureRecord

__all__ = [
    "DECIDED_BY_LIDAR",
    "DECIDED_BY_PAPER",
    "DECIDED_BY_REGISTRATION",
    "Hypothesis",
    "MatchReport",
    "RegistrationRecord",
]

# MatchReport.decided_by, what made the verdict unique:
DECIDED_BY_PAPER = "algorithm 1"  # one place by the features alone ...
DECIDED_BY_LIDAR = "lidar along the path"  # ... or one of several picked by the scans of the path ...
DECIDED_BY_REGISTRATION = "lidar registration"  # ... or a lidar registration (summary.json's too)


@dataclass
class Hypothesis:
    """One pose-distinct hypothesis (the best-ranked match of its group)."""

    rank: int
    storey: str
    assignment: tuple[int, ...]  # BIM index per confirmed feature, -1 = outlier
    matches: list[str | None]  # BIM IDs per confirmed feature, None = outlier
    n_outliers: int
    cost: float
    pose: Pose2D
    rectified_pose: Pose2D | None
    transform: Pose2D  # odom -> BIM
    confidence: float
    support: int  # matches merged into this hypothesis
    rectified: bool = False

    @property
    def reported_pose(self) -> Pose2D:
        """The pose the hypothesis reports: rectified (Eq. 17) when the storey has walls."""
        return self.rectified_pose or self.pose

    @property
    def n_inliers(self) -> int:
        """Confirmed features matched to a BIM feature (not declared outliers)."""
        return sum(m is not None for m in self.matches)


@dataclass(frozen=True)
class RegistrationRecord:
    """A unique lidar registration that a claim was made of (:mod:`initcli.verify.registration`): its
    fit, its best distinct rival's fit (None: none found), whether negative evidence counted (not
    when the camera had seen nothing) and, when places alike were ruled out by their beams through
    walls, the shares of such beams (the claim's, then theirs) and whether the map's doors were
    open for them (None otherwise)."""

    fit: float
    rival_fit: float | None
    negative_evidence: bool
    through: tuple[float, ...] | None = None
    doors_open: bool | None = None
    travel: float | None = None  # m of the log's travel at the claim (not written)
    t: float | None = None  # the log's time of the claim, s (not written)

    def as_dict(self) -> dict[str, object]:
        """The record as summary.json's coarse verification and ``match_result.schema.json``'s
        ``registration`` write it (shares rounded to 4 decimals)."""
        record: dict[str, object] = {
            "decided_by": DECIDED_BY_REGISTRATION,
            "registration_fit": round(self.fit, 4),
            "registration_rival_fit": None if self.rival_fit is None else round(self.rival_fit, 4),
            "negative_evidence": self.negative_evidence,
        }
        if self.through is not None:
            record["registration_through"] = [round(share, 4) for share in self.through]
            record["registration_doors_open"] = self.doors_open
        return record


@dataclass
class MatchReport:
    log: Path
    site: Path
    verdict: str  # the verdict line: verdict_text of the count (set with outcome by decide)
    outcome: Verdict
    storey: str | None
    storeys: list[str]
    features: list[ConfirmedFeature]
    hypotheses: list[Hypothesis]
    n_hypotheses: int
    odom_pose: Pose2D
    odom_path: np.ndarray  # (T, 3) robot poses in the odom frame
    options: MatchOptions
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    truth: Pose2D | None = None
    site_model: Site | None = field(default=None, repr=False)
    outliers_allowed: int = 0  # the outlier budget the hypotheses were found with (grown: outlier_share)
    overflow: bool = False  # matching stopped at the partial-match cap (far too ambiguous)
    decided_by: str | None = None  # what made the verdict unique: a DECIDED_BY_* of this module
    paper_verdict: str | None = None  # Algorithm 1's own verdict where the lidar changed it
    # the first unique lidar registration along the log that decided the verdict
    # (initcli.verify.registration), as summary.json records it
    registration: RegistrationRecord | None = None
    # every lidar landmark of the log, its records or those found in its scans (the verification's
    # negative evidence compares them with the storey's); None: not tracked (matching.landmarks off)
    landmarks: list[FeatureRecord] | None = None

    def decide(self, count: int) -> None:
        """The verdict of ``count`` pose-distinct hypotheses: its line and its outcome, together."""
        self.verdict, self.outcome = verdict_text(count), Verdict.of(count)

    def _storeys_poses(self) -> tuple[list[str], list[Pose2D], float, float]:
        hs = self.hypotheses
        return (
            [h.storey for h in hs],
            [h.reported_pose for h in hs],
            self.options.pose_radius,
            math.radians(self.options.beta),
        )

    def one_place(self) -> bool:
        """Do all the hypotheses (every one counted is listed) put the robot at one place now, within
        ``pose_radius`` and ``beta`` of the best by the poses they report (``one_place``)?"""
        return self.n_hypotheses <= len(self.hypotheses) and one_place(*self._storeys_poses())

    def weighted_inliers(self, hypothesis: Hypothesis) -> float:
        """The hypothesis's matched BIM features, a lidar landmark counting ``landmark_weight`` (what
        the claim checks weigh: corners are many and alike). A BIM feature matched again by a revisit
        counts once (at its heavier weight): the robot back at a door it saw before fits any place
        that has a door there, so the second sighting is no evidence for this place over another
        (a weak camera's claim 40 m off, block_b seed 60, passed on four matches of three doors)."""
        lidar = self.options.landmark_matching().classes
        w = self.options.landmark_weight
        weights: dict[str, float] = {}
        for f, m in zip(self.features, hypothesis.matches, strict=False):
            if m is not None:
                weights[m] = max(weights.get(m, 0.0), w if f.cls in lidar else 1.0)
        return sum(weights.values())

    def places(self) -> list[int]:
        """Indices of the listed hypotheses, one per place (``distinct_places``)."""
        return distinct_places(*self._storeys_poses())
