"""``bim-init match``: a detection log and a site model in, ranked pose hypotheses and a verdict out.

Pipeline (paper §3.3.1-3.3.3, §3.3.5), each step a pure function of :mod:`initcli.core`:

1. Eq. 1-2 -- every detected box (centre + depth) to a point in the odom frame;
2. the detection filter -- sightings to confirmed features S_object (Eq. 3);
3. Algorithm 1 (Eq. 4-9) with outlier tolerance, on every storey searched;
4. sub-matches dropped, ranking by (outliers, cost J of Eq. 14), pose-distinct counting;
5. the pose of each shown hypothesis at the log's last odom record (Eq. 10-13 or rigid);
6. BIM rectification (Eq. 17) with the storey's walls;
7. the verdict: ``unique match`` (exit 0), ``N hypotheses`` (exit 3), ``no consistent match`` (exit 4).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bimkit.checks import read_yaml
from bimkit.errors import InputError
from bimtools.site.load import Site, StoreyModel, load_site
from bimtools.site.records import LIDAR
from initcli.config.matching import MatchOptions
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import (
    ConfirmedFeature,
    GivenFeature,
    Sighting,
    filter_detections,
    within_drift_window,
)
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.hypotheses.matching import OUTLIER, BimIndex, Matcher, MatchOverflow, MatchParams
from initcli.core.hypotheses.pose import estimate_pose, rigid_align_batch
from initcli.core.hypotheses.ranking import (
    confidences,
    distinct_places,
    drop_dominated,
    one_place,
    pose_groups,
    rank_order,
    verdict_text,
)
from initcli.core.hypotheses.rectify import WallArray, rectify_pose
from initcli.io.detection_log import DetectionLog, FeatureRecord, read_log
from initcli.match.landmarks import combined_sequence, log_landmarks, recent_landmarks, travel_at
from initcli.match.sightings import sightings_from_log

__all__ = [
    "DECIDED_BY_LIDAR",
    "DECIDED_BY_PAPER",
    "ESCALATED_PARTIALS",
    "EXIT_AMBIGUOUS",
    "EXIT_BAD_INPUT",
    "EXIT_NO_MATCH",
    "EXIT_UNIQUE",
    "Hypothesis",
    "MatchOptions",
    "MatchReport",
    "check_classes",
    "current_odom",
    "match_log",
    "run_match",
    "site_class_map",
    "transform_poses_batch",
]

EXIT_UNIQUE = 0
DECIDED_BY_PAPER = "algorithm 1"  # MatchReport.decided_by: one place by the features alone ...
DECIDED_BY_LIDAR = "lidar along the path"  # ... or one of several picked by the scans of the path
EXIT_BAD_INPUT = 2
EXIT_AMBIGUOUS = 3
EXIT_NO_MATCH = 4

ESCALATED_PARTIALS = 2_000_000  # partial-match cap once the outlier budget grows (memory, time)


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


@dataclass
class MatchReport:
    log: Path
    site: Path
    verdict: str
    exit_code: int
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
    decided_by: str | None = None  # what made the verdict unique: DECIDED_BY_PAPER, DECIDED_BY_LIDAR, or
    # initcli.verify.registration's DECIDED_BY_REGISTRATION
    paper_verdict: str | None = None  # Algorithm 1's own verdict where the lidar changed it
    # the first unique lidar registration along the log that decided the verdict
    # (initcli.verify.registration):
    # its fit, its best distinct rival's fit and whether the camera's misses counted, as summary.json
    registration: dict[str, object] | None = None
    # every lidar landmark of the log, its records or those found in its scans (the verification's
    # negative evidence compares them with the storey's); None: not tracked (matching.landmarks off)
    landmarks: list[FeatureRecord] | None = None

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


# --- inputs ----------------------------------------------------------------------------------------


def site_class_map(site: Site) -> ClassMap:
    """The site's optional class mapping ``{detector class name: feature category}``.

    Looked up in the site folder: ``site.yaml`` (the ``bim-init run`` site config,
    ``detector.classes``; schemas/site_config.schema.json), then ``"classes"`` in ``site.json``.
    A bare features.csv has no mapping (the built-in synonyms still apply).
    """
    root = Path(site.root)
    if not root.is_dir():
        return ClassMap()
    for path, keys in ((root / "site.yaml", ("detector", "classes")), (root / "site.json", ("classes",))):
        if not path.exists():
            continue
        doc = read_yaml(path, "the class mapping")  # YAML also reads JSON
        mapping = doc
        for key in keys:
            mapping = mapping.get(key) if isinstance(mapping, dict) else None
        if mapping is None:
            continue
        if not isinstance(mapping, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in mapping.items()
        ):
            where = ".".join(keys)
            raise InputError(f"{path}: {where} must map detector class names to feature categories")
        return ClassMap(mapping)
    return ClassMap()


def check_classes(log: DetectionLog, cmap: ClassMap, site: Site) -> None:
    """Every class name in the log must map to a known feature class (else one line, exit 2)."""
    categories = [f.category for s in site.storeys.values() for f in s.features]
    known = cmap.known(categories)
    unknown: set[str] = set()
    for rec in log.detections:
        unknown.update(o.cls for o in rec.objects if cmap.canonical(o.cls) not in known)
    unknown.update(f.cls for f in log.features if f.source != LIDAR and cmap.canonical(f.cls) not in known)
    if unknown:
        names = ", ".join(repr(n) for n in sorted(unknown))
        raise InputError(
            f"{log.path}: unknown class name(s) {names}; known: {', '.join(sorted(known))} "
            "(map other names with detector.classes in the site folder's site.yaml)"
        )


def current_odom(log: DetectionLog) -> tuple[Pose2D, np.ndarray, list[str]]:
    """The robot's odom pose at the last odom record, the odom path, and a warning if improvised."""
    odom = log.odom
    if odom:
        path = np.array([[o.x, o.y, o.yaw] for o in odom])
        return odom[-1].pose, path, []
    dets = log.detections
    if dets:
        path = np.array([[d.pose.x, d.pose.y, d.pose.yaw] for d in dets])
        return (
            dets[-1].pose,
            path,
            [f"{log.path}: no odom records; using the pose of the last detections record"],
        )
    return (
        Pose2D.identity(),
        np.zeros((1, 3)),
        [f"{log.path}: no odom records; assuming the robot is at the odom origin"],
    )


# --- matching --------------------------------------------------------------------------------------


@dataclass
class _Candidates:
    storey: list[str] = field(default_factory=list)
    assign: list[np.ndarray] = field(default_factory=list)
    n_out: list[np.ndarray] = field(default_factory=list)
    cost: list[np.ndarray] = field(default_factory=list)
    transform: list[np.ndarray] = field(default_factory=list)  # (H, 3) odom->BIM x, y, yaw
    indexes: dict[str, BimIndex] = field(default_factory=dict)  # per storey


def _storey_candidates(
    model: StoreyModel,
    cmap: ClassMap,
    s_xy: np.ndarray,
    s_cls: Sequence[str],
    params: MatchParams,
    s_travel: np.ndarray | None = None,
) -> tuple[BimIndex, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    index = BimIndex(
        np.array([[f.x, f.y] for f in model.features]), [cmap.canonical(f.category) for f in model.features]
    )
    matcher = Matcher(index, params)
    state = matcher.match(s_xy, s_cls, s_travel)
    rows = state.matches(params)
    assign, n_out, cost = state.assign[rows], state.n_out[rows], state.cost[rows]
    # rule 1 over the camera's outliers and the camera's columns: with the landmarks' columns in the
    # outlier set, a hypothesis with a false door and a skipped corner dominated itself and vanished
    # (a landmark sub-match has the pose of its match: rule 3 merges them)
    camera = np.array([not params.is_landmark(c) for c in s_cls], dtype=bool)
    keep = drop_dominated(assign[:, camera], n_out)
    assign, n_out, cost = assign[keep], n_out[keep], cost[keep]
    if len(assign):
        inlier = assign != OUTLIER
        bim = index.xy[np.where(inlier, assign, 0)]
        src = np.broadcast_to(s_xy, bim.shape)
        yaw, t = rigid_align_batch(src, bim, inlier.astype(float))
        transform = np.column_stack([t, yaw])
    else:
        transform = np.zeros((0, 3))
    return index, assign, n_out, cost, transform


def transform_poses_batch(transforms: np.ndarray, pose: Pose2D) -> np.ndarray:
    """``T_h * pose`` for every transform row (x, y, yaw) of ``transforms`` -> (H, 3)."""
    c, s = np.cos(transforms[:, 2]), np.sin(transforms[:, 2])
    x = transforms[:, 0] + c * pose.x - s * pose.y
    y = transforms[:, 1] + s * pose.x + c * pose.y
    return np.column_stack([x, y, wrap_angle(transforms[:, 2] + pose.yaw)])


def run_match(
    log_path: Path | str,
    site_path: Path | str,
    options: MatchOptions | None = None,
    source: Path | str | None = None,
) -> MatchReport:
    """The whole ``bim-init match`` pipeline; raises :class:`InputError` on bad input.

    The class mapping is the site folder's (:func:`site_class_map`). ``source``: the file the user
    named, when ``log_path`` was converted from it (a bag), for the messages.
    """
    opts = options or MatchOptions()
    opts.validate()
    log = read_log(log_path, skip_bad=opts.skip_bad)
    _check_depths(log, source if source is not None else log.path)
    site = load_site(Path(site_path), with_maps=False)
    return match_log(log, site, opts, site_class_map(site))


def _check_depths(log: DetectionLog, name: Path | str) -> None:
    """Refuse a log whose camera detections all lack a depth: Eq. 1 places a box by its depth, so
    none would become a sighting (and the match would end in 0 features with no reason given)."""
    objects = [o for d in log.detections for o in d.objects]
    if objects and not any(o.depth is not None and math.isfinite(o.depth) for o in objects):
        raise InputError(
            f"{name}: none of the {len(objects)} detections has a depth (every 'depth' is null): "
            "a detection is placed by its depth (Eq. 1); record or convert with an aligned depth image"
        )


def match_log(
    log: DetectionLog,
    site: Site,
    opts: MatchOptions,
    cmap: ClassMap,
    sightings: Sequence[Sighting] | None = None,
) -> MatchReport:
    """The pipeline on an already-read log and site.

    ``sightings``: the log's sightings (Eq. 1-2) when the caller already holds them, as the online
    session does (it converts each image as it arrives with the same code and ``edge_margin``).

    ``cmap`` maps the log's class names to the site's feature categories: the site folder's mapping
    for ``bim-init match`` (:func:`site_class_map`), the session config's ``detector.classes`` for
    ``bim-init run``. Nothing is read from disk here.
    """
    check_classes(log, cmap, site)
    warnings = list(log.warnings)
    notes: list[str] = []
    features, landmarks, odom_pose, odom_path = _confirmed_features(
        log, site, opts, cmap, sightings, warnings, notes
    )
    if not log.detections and not log.features:
        notes.append("the log has no detections records")
    storey_names = _storeys_searched(site, opts)
    report = MatchReport(
        log=log.path,
        site=Path(site.root),
        verdict=verdict_text(0),
        exit_code=EXIT_NO_MATCH,
        storey=None,
        storeys=storey_names,
        features=features,
        hypotheses=[],
        n_hypotheses=0,
        odom_pose=odom_pose,
        odom_path=odom_path,
        options=opts,
        warnings=warnings,
        notes=notes,
        truth=log.truth[-1].pose if log.truth else None,
        site_model=site,
        landmarks=landmarks,
    )
    if len(features) < opts.min_inliers:
        notes.append(
            f"{len(features)} confirmed feature(s); a hypothesis needs at least {opts.min_inliers} "
            f"(a feature is confirmed after {opts.min_sightings} sightings)"
        )
        return report

    # Step 3-4: Algorithm 1 on every storey, then rule 1 (sub-matches) per storey; with no match,
    # one more outlier at a time up to the outlier_share budget. With lidar landmarks: the mixed
    # sequence first (the camera's max_outliers; with two camera features or more every landmark
    # may be an outlier and joins a candidate once it holds two: MatchOptions.landmark_matching);
    # when it has no match, the camera's features alone as without landmarks (landmarks of
    # geometry the BIM lacks never cost a camera match).
    params = opts.match_params()
    camera = [f for f in features if not params.is_landmark(f.cls)]
    if len(camera) < len(features):
        found = _search(report, site, cmap, storey_names, features, log, opts, escalate=False)
        if found is not None and found.storey:
            if len(camera) < 2 and (report.n_hypotheses == 1 or report.one_place()):
                # Landmarks matched alone to one place within landmark_outlier_share: that verdict
                # stands only as the one with every landmark allowed to be an outlier (at most
                # ESCALATED_PARTIALS partial matches). The budget can rule out the true place and
                # leave a chance or mirror fit (ntu_hallway, camera off, seed 16: a claim 71 m off,
                # turned half round, its true place ruled out in the rival search too).
                budgeted = report.verdict
                every = replace(opts, landmark_outlier_share=1.0)
                _search(report, site, cmap, storey_names, features, log, every, False, ESCALATED_PARTIALS)
                if report.exit_code != EXIT_UNIQUE:
                    notes.append(
                        f"{budgeted} within the lidar landmarks' outlier budget; {report.verdict} with"
                        " every landmark allowed to be geometry the BIM lacks"
                    )
            return report
        if found is None and not camera:
            return report  # the landmarks' search overflowed, the camera saw nothing: far too ambiguous
        if found is None:  # the landmarks' search overflowed: the camera's alone decide
            report.overflow, report.n_hypotheses = False, 0
            report.verdict, report.exit_code = verdict_text(0), EXIT_NO_MATCH
        if len(camera) < opts.min_inliers:
            return report
        notes.append(
            f"no match with the {len(features) - len(camera)} lidar landmark(s); matched the camera's "
            f"{len(camera)} feature(s) alone"
        )
        report.features = features = _renumbered(camera)
    _search(report, site, cmap, storey_names, features, log, opts, escalate=True)
    return report


def _renumbered(features: Sequence[ConfirmedFeature]) -> list[ConfirmedFeature]:
    return [replace(f, index=i) for i, f in enumerate(features)]


def _search(
    report: MatchReport,
    site: Site,
    cmap: ClassMap,
    storey_names: list[str],
    features: list[ConfirmedFeature],
    log: DetectionLog,
    opts: MatchOptions,
    escalate: bool,
    max_partials: int | None = None,
) -> _Candidates | None:
    """Steps 3-7 on ``features`` into ``report`` (the camera's outlier budget grown when ``escalate``;
    ``max_partials``: a lower partial-match cap than MatchParams'); the candidates, or None when
    matching stopped at the partial-match cap."""
    s_xy = np.array([[f.x, f.y] for f in features]).reshape(-1, 2)
    s_cls = [f.cls for f in features]
    s_travel = travel_at(log.odom, [f.t_confirmed for f in features])
    is_landmark = opts.match_params().is_landmark
    n_camera = sum(not is_landmark(c) for c in s_cls)
    params = opts.match_params(camera=n_camera >= 2)
    if max_partials is not None:
        params = replace(params, max_partials=max_partials)
    budget = opts.outlier_budget(n_camera) if escalate else 0
    while True:
        try:
            cand = _candidates(site, cmap, storey_names, s_xy, s_cls, params, s_travel)
        except MatchOverflow as exc:
            report.warnings.append(f"matching stopped: {exc}; the detected pattern is far too ambiguous")
            report.verdict = verdict_text(max(2, params.max_partials))
            report.exit_code = EXIT_AMBIGUOUS
            report.n_hypotheses = params.max_partials
            report.overflow = True
            return None
        if cand.storey or params.max_outliers >= budget:
            break
        params = replace(params, max_outliers=params.max_outliers + 1, max_partials=ESCALATED_PARTIALS)
    if params.max_outliers > opts.max_outliers and cand.storey:
        report.notes.append(
            f"no match tolerates {opts.max_outliers} outlier(s); matched with {params.max_outliers} "
            f"(outlier_share {opts.outlier_share:g} of {len(features)} features)"
        )
    report.outliers_allowed = params.max_outliers
    if cand.storey:
        _rank(report, site, cand, s_xy)
    return cand


def _confirmed_features(
    log: DetectionLog,
    site: Site,
    opts: MatchOptions,
    cmap: ClassMap,
    sightings: Sequence[Sighting] | None,
    warnings: list[str],
    notes: list[str],
) -> tuple[list[ConfirmedFeature], list[FeatureRecord] | None, Pose2D, np.ndarray]:
    """Steps 1-2: Eq. 1-2 and the detection filter, the lidar landmarks joined in
    (:mod:`initcli.match.landmarks`) and all within the drift window when one is set; every lidar
    landmark of the log (None: ``opts.landmarks`` off); the robot's odom pose now and its odom path."""
    if sightings is None:
        sightings = sightings_from_log(log, cmap, opts.edge_margin)
    given = [GivenFeature(f.t, cmap.canonical(f.cls), f.x, f.y) for f in log.features if f.source != LIDAR]
    filtered = filter_detections(sightings, opts.filter_params(), given)
    lidar: list[FeatureRecord] = []
    found: list[FeatureRecord] | None = None
    if opts.landmarks:
        found = log_landmarks(log, site, notes)
        lidar = recent_landmarks(found, log.odom, opts.landmark_window, site, cmap)
        if len(lidar) < len(found):
            notes.append(
                f"matched {len(lidar)} of {len(found)} lidar landmark(s): of a category the site has, "
                f"confirmed in the last {opts.landmark_window:g} m of travel"
            )
    features = combined_sequence(filtered.features, lidar, cmap)
    odom_pose, odom_path, more = current_odom(log)
    warnings.extend(more)
    if opts.drift_window is not None and log.odom and len(features) > opts.min_inliers:
        odom_t = np.array([o.t for o in log.odom])
        recent = within_drift_window(features, odom_t, odom_path[:, :2], opts.drift_window, opts.min_inliers)
        if len(recent) < len(features):
            notes.append(
                f"matched the {len(recent)} features confirmed in the last {opts.drift_window:g} m of "
                f"travel; {len(features) - len(recent)} older one(s) left out (odometry drift)"
            )
            features = recent
    return features, found, odom_pose, odom_path


def _storeys_searched(site: Site, opts: MatchOptions) -> list[str]:
    """Every storey (``storey`` None or auto) or the one named (InputError listing the valid ones)."""
    if opts.storey is None or opts.storey == "auto":
        return list(site.storeys)
    site.storey(opts.storey)  # raises InputError listing the valid storeys
    return [opts.storey]


def _candidates(
    site: Site,
    cmap: ClassMap,
    storey_names: list[str],
    s_xy: np.ndarray,
    s_cls: Sequence[str],
    params: MatchParams,
    s_travel: np.ndarray | None = None,
) -> _Candidates:
    """Algorithm 1 and rule 1 on every storey searched (MatchOverflow past the partial-match cap)."""
    cand = _Candidates()
    for name in storey_names:
        model = site.storeys[name]
        index, assign, n_out, cost, transform = _storey_candidates(model, cmap, s_xy, s_cls, params, s_travel)
        cand.indexes[name] = index
        cand.storey.extend([name] * len(assign))
        cand.assign.append(assign)
        cand.n_out.append(n_out)
        cand.cost.append(cost)
        cand.transform.append(transform)
    return cand


def _rank(report: MatchReport, site: Site, cand: _Candidates, s_xy: np.ndarray) -> None:
    """Steps 4-7 on the candidates of every storey: rank (rule 2), group by pose (rule 3), the
    confidences (rule 5), the pose of each shown hypothesis, and the verdict, into ``report``."""
    opts, odom_pose = report.options, report.odom_pose
    assign = np.concatenate(cand.assign)
    n_out = np.concatenate(cand.n_out)
    cost = np.concatenate(cand.cost)
    transform = np.concatenate(cand.transform)
    storey_ids = np.array([report.storeys.index(s) for s in cand.storey])
    current = transform_poses_batch(transform, odom_pose)  # robot pose in BIM per match (rigid)
    # rule 2: camera outliers first, then the lidar landmarks' (clutter is common: they weigh less)
    order = rank_order(n_out * (assign.shape[1] + 1) + (assign == OUTLIER).sum(axis=1), cost)
    labels, reps = pose_groups(
        current, storey_ids, order, opts.pose_radius, math.radians(opts.beta)
    )  # rule 3
    support = np.bincount(labels, minlength=len(reps))
    conf = confidences(cost[reps], n_out[reps])  # rule 5

    hyps: list[Hypothesis] = []
    for rank, h in enumerate(reps[: opts.top], start=1):
        storey = cand.storey[h]
        model = site.storeys[storey]
        row = assign[h]
        pose, rect_pose, moved = _hypothesis_pose(model, cand.indexes[storey], row, s_xy, odom_pose, opts)
        hyps.append(
            Hypothesis(
                rank=rank,
                storey=storey,
                assignment=tuple(int(a) for a in row),
                matches=[model.features[int(a)].id if a != OUTLIER else None for a in row],
                n_outliers=int(n_out[h]),
                cost=float(cost[h]),
                pose=pose,
                rectified_pose=rect_pose,
                transform=pose * odom_pose.inverse(),
                confidence=float(conf[rank - 1]),
                support=int(support[labels[h]]),
                rectified=moved,
            )
        )
    report.hypotheses = hyps
    report.n_hypotheses = len(reps)
    report.verdict = verdict_text(len(reps))
    report.exit_code = EXIT_UNIQUE if len(reps) == 1 else EXIT_AMBIGUOUS
    report.decided_by = DECIDED_BY_PAPER if len(reps) == 1 else None
    rep_storeys = {cand.storey[h] for h in reps}
    report.storey = next(iter(rep_storeys)) if len(rep_storeys) == 1 else None


def _hypothesis_pose(
    model: StoreyModel,
    index: BimIndex,
    row: np.ndarray,
    s_xy: np.ndarray,
    odom_pose: Pose2D,
    opts: MatchOptions,
) -> tuple[Pose2D, Pose2D | None, bool]:
    """Steps 5-6 for one match: the robot's pose now (Eq. 10-13 or rigid), rectified with the
    storey's walls (Eq. 17) when it has walls, and whether rectification moved it."""
    inl = np.flatnonzero(row != OUTLIER)
    bim_xy = index.xy[row[inl]]
    pose = estimate_pose(opts.pose_method, bim_xy, s_xy[inl], odom_pose, opts.pose_window or None)
    if not model.walls:
        return pose, None, False
    walls = WallArray.from_segments([(w.x1, w.y1, w.x2, w.y2, *w.normal) for w in model.walls])
    feature_robot = odom_pose.apply_inverse(s_xy[inl[-1]])
    rect_pose, rect = rectify_pose(  # Eq. 17, never turning the pose past beta
        pose, walls, opts.d_thre, bim_xy[-1], feature_robot, math.radians(opts.beta)
    )
    return pose, rect_pose, rect.moved
