"""The options of ``bim-init match``, each written once with its unit, range and one default.

:class:`MatchingSettings` are the matching tunables the ``matching:`` section of the session config
shares with the command (the section is a subclass that adds the session's own); :class:`MatchOptions`
adds what only the command and the pipeline take. The command's options
(:mod:`initcli.cli.match`), the site config's schema and the range checks are derived from these
fields (:mod:`bimkit.settings`). Units are the user's: metres, degrees (``beta``), pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from bimkit.errors import InputError
from bimkit.settings import check_ranges, setting, shared
from bimtools.site.records import LANDMARK_CATEGORIES
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import FilterParams
from initcli.core.hypotheses.matching import LandmarkMatching, MatchParams
from initcli.core.hypotheses.pose import POSE_METHODS

__all__ = ["D_THRE", "DEFAULT_POSE_METHOD", "SCORE_THRESHOLD", "MatchOptions", "MatchingSettings"]

# Measured on noisy synthetic logs over the three sample models (benchmarks/bench_match.py, "pose
# accuracy", 43 unique correct matches): rigid 0.062 m / 0.84 deg mean error, paper (Eq. 10-13)
# 0.115 m / 2.20 deg. The paper's method uses only the last three features and wins slightly in
# position where odometry drift dominates (ntu_hallway: 0.075 vs 0.093 m), never in heading.
DEFAULT_POSE_METHOD = "rigid"

# Settings the session config keeps in other sections (exploration.d_thre, detector.score_threshold).
D_THRE = shared(0.5, "m: wall clearance of Eq. 17", minimum=0, maximum=10, metavar="M")
SCORE_THRESHOLD = shared(
    0.5, "detections scoring lower are ignored (the detection filter)", minimum=0, maximum=1, metavar="S"
)


@dataclass
class MatchingSettings:
    """The matching tunables of ``bim-init match`` that the ``matching:`` section of site.yaml sets."""

    # The paper uses 0.5; on sites as built (doors 0.3 m off their place, a 2 % odometry scale error)
    # 0.8 initialised 49 of 60 construction starts against 44 at 0.5, with no wrong claim at either
    # and 59 against 60 of 60 in the ideal world (eval, 20 starts per sample).
    alpha: float = setting(
        0.8,
        "m: distance threshold of Eq. 7 (the paper: 0.5; 0.8 tolerates doors built 0.3 m off their"
        " place and a 2 % odometry scale error)",
        above=0,
        maximum=50,
        metavar="M",
    )
    beta: float = setting(
        15.0, "degrees: angle threshold of Eq. 9", above=0, maximum=180, metavar="DEG"
    )  # radians only inside initcli.core
    max_outliers: int = setting(
        1,
        "false or misclassified detections tolerated (the search grows combinatorially)",
        minimum=0,
        maximum=10,
        metavar="N",
    )
    outlier_share: float = setting(
        0.34,
        "with no match at max_outliers, the outlier budget grows one at a time up to this share of the"
        " confirmed features (sites as built: extra doors, posters, shifted doors are a steady share of"
        " a long sequence); 0: max_outliers alone",
        minimum=0,
        maximum=0.5,
        metavar="S",
    )
    revisits: bool = setting(
        True,
        "a later detection may match a BIM feature matched before (the robot came back); false: the"
        " literal Algorithm 1",
        flag="--revisits/--no-revisits",
    )
    pose_method: str = setting(
        DEFAULT_POSE_METHOD,
        "the pose of a hypothesis: paper (Eq. 10-13, the last three features) or rigid (Kabsch on the"
        " matches)",
        enum=POSE_METHODS,
        metavar="paper|rigid",
    )
    pose_window: int = setting(
        4,
        "rigid: align the last N matched features (odometry drifts); 0: all of them",
        minimum=0,
        maximum=10000,
        metavar="N",
    )
    min_sightings: int = setting(
        3, "sightings that confirm a feature (k of the detection filter)", above=0, maximum=1000, metavar="K"
    )
    merge_radius: float = setting(
        1.0, "m: same-class sightings closer than this merge", above=0, maximum=50, metavar="M"
    )
    # The detection filter's depth limits: a sighting whose depth (the mean of the depth window)
    # lies outside [min_depth, max_depth] is not used (depth noise grows with range).
    min_depth: float = setting(
        0.1, "m: detections with a depth below this are ignored", minimum=0, maximum=100, metavar="M"
    )
    max_depth: float = setting(
        10.0, "m: detections with a depth above this are ignored", above=0, maximum=100, metavar="M"
    )
    edge_margin: float = setting(
        2.0,
        "px: boxes this close to the left/right image border are cut off and not used; < 0 keeps them",
        minimum=-10000,
        maximum=10000,
        metavar="PX",
    )
    # Lidar landmarks (wall corners, column corners, openings; beyond the paper): used when the site
    # has them (bim-extract's landmarks: block) and the log has them or scans to find them in.
    landmarks: bool = setting(
        True,
        "match the lidar landmarks too when the site has them (the log's lidar feature records, or those"
        " found in its scans); false: the camera's features alone",
        flag="--landmarks/--no-landmarks",
    )
    landmark_alpha: float = setting(
        0.15,
        "m: distance threshold of Eq. 7 between two lidar landmarks confirmed at the same travel (scan"
        " landmarks are cm-accurate; the camera's alpha would let thousands of corners share a pattern)",
        above=0,
        maximum=50,
        metavar="M",
    )
    landmark_drift: float = setting(
        0.02,
        "m per m of odometry travel between two lidar landmarks' confirmations, added to landmark_alpha"
        " (odometry drift between the sightings dominates over the scan's accuracy)",
        minimum=0,
        maximum=1,
        metavar="M/M",
    )
    landmark_window: float = setting(
        30.0,
        "m: match only the lidar landmarks confirmed in the last M metres of travel (clutter is common and"
        " the search grows with every landmark; odometry drifts); 0: all of them",
        minimum=0,
        maximum=100000,
        metavar="M",
    )
    landmark_weight: float = setting(
        0.5,
        "what one matched lidar landmark counts toward min_inliers (a camera feature counts 1): corners"
        " are many, so patterns of landmarks need more members",
        above=0,
        maximum=1,
        metavar="W",
    )
    # 0.34: bench_matcher_scale meets the speed goals (1: 7.2 ms median per update at 1,000 features)
    landmark_outlier_share: float = setting(
        0.34,
        "share of the lidar landmarks a match of landmarks alone (the camera saw nothing) may declare"
        " outliers (at least one), a budget apart from the camera's (geometry the BIM lacks: material"
        " stacks, hoardings, furniture, open door leaves); with camera features every landmark may be one",
        minimum=0,
        maximum=1,
        metavar="S",
    )


@dataclass
class MatchOptions(MatchingSettings):
    """Every tunable of ``bim-init match``, each with its one default (those of
    :class:`MatchingSettings` first)."""

    storey: str | None = None  # None or "auto": every storey when the site has several
    top: int = setting(5, "hypotheses shown (the most probable first)", minimum=1, maximum=10000, metavar="K")
    min_inliers: int = setting(3, "matched features needed for a hypothesis (paper 3.3.4)", minimum=2)
    drift_window: float | None = setting(
        None,
        "m: match only the features confirmed in the last M metres of travel (odometry drift)",
        above=0,
        maximum=100000,
        metavar="M",
    )
    d_thre: float = D_THRE()
    pose_radius: float = setting(
        1.0, "m: hypotheses closer than this (and within beta in yaw) are one", maximum=100
    )
    score_threshold: float = SCORE_THRESHOLD()
    skip_bad: bool = setting(
        False, "skip malformed log lines (with a count) instead of failing", flag="--skip-bad"
    )
    registration: bool = setting(
        True,
        "with no unique verdict, register the lidar submap of the log's last registration.window m over"
        " the site's maps, as a session does with no camera claim (needs the site folder's maps and the"
        " log's scans); false: the features and the lidar along the path alone",
        flag="--registration/--no-registration",
    )

    def outlier_budget(self, features: int) -> int:
        """The most outliers a match of ``features`` confirmed features may declare: max_outliers,
        grown to outlier_share of them."""
        return max(self.max_outliers, int(self.outlier_share * features))

    def match_params(self, camera: bool = False) -> MatchParams:
        """Algorithm 1's parameters; ``camera``: the sequence has camera features
        (:meth:`landmark_matching`)."""
        return MatchParams(
            alpha=self.alpha,
            beta=math.radians(self.beta),
            max_outliers=self.max_outliers,
            min_inliers=self.min_inliers,
            revisits=self.revisits,
            landmarks=self.landmark_matching(camera) if self.landmarks else None,
        )

    def landmark_matching(self, camera: bool = False) -> LandmarkMatching:
        """How Algorithm 1 treats the lidar landmarks (canonical class names of LANDMARK_CATEGORIES).
        ``camera``: the sequence has two or more camera features, so every landmark may be an outlier
        (most a lidar sees in a corridor are material stacks' corners: 64 % of the confirmed ones in
        the simulated samples, 70 % as built) and joins a candidate only once it holds two camera
        features; else (the camera saw next to nothing) ``landmark_outlier_share`` of them, and
        landmarks start candidates."""
        return LandmarkMatching(
            classes=frozenset(ClassMap().canonical(c) for c in LANDMARK_CATEGORIES),
            alpha=self.landmark_alpha,
            drift=self.landmark_drift,
            weight=self.landmark_weight,
            outlier_share=1.0 if camera else self.landmark_outlier_share,
            anchored=camera,
        )

    def filter_params(self) -> FilterParams:
        return FilterParams(
            merge_radius=self.merge_radius,
            min_sightings=self.min_sightings,
            score_threshold=self.score_threshold,
            min_depth=self.min_depth,
            max_depth=self.max_depth,
            edge_margin=self.edge_margin,
        )

    def validate(self) -> None:
        """Every option finite, within its range and among its values (the ranges of the fields, the
        same as the site config schema's); else one :class:`InputError` naming the option."""
        check_ranges(self, lambda name: f"--{name.replace('_', '-')}")
        if not self.min_depth < self.max_depth:
            raise InputError("--min-depth must be below --max-depth")
