"""Verification of a match's hypotheses against the log: negative evidence and the lidar's fit.

:mod:`initcli.core.verify.checks` holds the checks; this module gathers their inputs from a detection
log (its images' odom poses, every sighting, the scans) and a site storey (the BIM features, walls
and map). The online session and ``bim-init match`` both call :func:`verify_transform`, so a
session's verdict replays from its log.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Protocol, TypeVar

import numpy as np

from bimtools.site.load import Site, StoreyModel, load_site
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import Sighting
from initcli.core.filters.particle_filter import LikelihoodField, likelihood_field
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.scan_fit import ScanSample
from initcli.core.lidar.wall_beams import wall_beams
from initcli.core.verify.checks import (
    TRACK_HYPOTHESES,
    CameraView,
    FreeSpace,
    LandmarkEvidence,
    LandmarkView,
    PathTrack,
    Verification,
    judge,
    track_favoured,
    tracked_scan_fit,
    verify_hypothesis,
)
from initcli.core.verify.params import VerificationParams
from initcli.io.detection_log import DetectionLog, Detections, Odom, Scan, read_log
from initcli.match.load import site_class_map
from initcli.match.report import DECIDED_BY_LIDAR, DECIDED_BY_PAPER, MatchReport
from initcli.match.sightings import sightings_from_log

__all__ = [
    "LANDMARK_WINDOW_M",
    "MAX_SCANS",
    "PATH_CHECK_M",
    "PATH_RETRY",
    "PATH_WINDOW_M",
    "PathEvidence",
    "RECENT_SCANS_M",
    "SCAN_BEAM_STEP",
    "StoreyEvidence",
    "TRACK_BEAM_STEP",
    "TRACK_KEPT_M",
    "TRACK_STEP_M",
    "SEEING_FEATURES",
    "camera_blind",
    "check_hypotheses",
    "check_loaded",
    "claim_params",
    "lidar_unique",
    "path_free_along",
    "path_track",
    "refuse_unique",
    "track_transform",
    "verify_and_favour",
    "verify_report",
    "verify_transform",
    "without_landmark_misses",
]

SCAN_BEAM_STEP = 3  # every third beam is enough for a fit share
RECENT_SCANS_M = 8.0  # m of the latest travel whose scans are fitted (older ones carry odometry drift)
MAX_SCANS = 16  # scans fitted at most, the latest first
PATH_WINDOW_M = 60.0  # m of the latest travel whose images predict features
LANDMARK_WINDOW_M = 20.0  # m of the latest travel whose scans predict lidar landmarks (older
# landmarks carry odometry drift: a room passed 40 m before was confirmed a metre off its corners)
PATH_CHECK_M = 30.0  # m of the latest travel that must lie in the BIM's free space ...
PATH_RETRY = 0.2  # ... placed window by window by the lidar along the path when one transform leaves
# it at most this much short
TRACK_STEP_M = 0.5  # m of travel between the scans kept for the lidar along the path ...
TRACK_BEAM_STEP = 2  # ... with every second of their beams
TRACK_KEPT_M = 100.0  # m of travel whose scans are kept for it (the check reads track_m of them)

# Confirmed camera features (Eq. 3) that show a camera sees the features a place predicts, so that
# the ones it missed count against a place (negative evidence). A false box now and then is one
# sighting in one image, never repeated where it landed, and confirms nothing; a poster taken for a
# door every time it is in view confirms one feature. Neither shows a working camera: with one
# false box a minute and the camera otherwise blind, the doors it "missed" held back the true place
# of a lidar registration (10/10 -> 7/10 sessions ideal, 15/15 -> 9/15 as built). A working camera
# confirms each door it passes (sim.miss_rate 0.1: several within metres), so its misses still
# refuse a wrong place.
SEEING_FEATURES = 2

P = TypeVar("P", bound=VerificationParams)
LANDMARK_CLASSES = ClassMap()  # the landmark categories' canonical names (LandmarkMatching's)


class Located(Protocol):
    """A confirmed feature or a feature record: its class and odom position."""

    @property
    def cls(self) -> str: ...
    @property
    def x(self) -> float: ...
    @property
    def y(self) -> float: ...


def camera_blind(images: int, confirmed: int) -> bool:
    """Does a camera that took ``images`` and confirmed ``confirmed`` features (Eq. 3, the camera's
    only) see nothing useful: it took images yet confirmed fewer than :data:`SEEING_FEATURES`? Raw
    sightings do not tell: a false box now and then is a sighting too. Independent of any place (a
    working camera at a wrong place has seen the real doors there, confirmed, that place does not
    explain)."""
    return images > 0 and confirmed < SEEING_FEATURES


def claim_params(params: P, blind: bool) -> P:
    """The checks a claim passes: ``params``, with negative evidence off when the camera is
    ``blind`` (:func:`camera_blind`: it took images but confirmed next to nothing, the camera is
    off or sees nothing useful, so a feature predicted in view and missed says nothing of the
    place, it would be missed anywhere). The session's claims and ``bim-init match``'s replay of a
    lidar registration both use it."""
    return replace(params, log_odds=math.inf) if blind else params


def without_landmark_misses(params: P) -> P:
    """``params`` with the lidar landmarks' misses left out: the checks of a rival, of one of several
    places, of a fine pose. The misses may hold back a coarse claim, never rule out a rival (a rival
    ruled out lets a claim through): at the true place a quarter to a third of the predicted corners
    go unseen (furniture and stacks hide them, several at once)."""
    return replace(params, landmark_log_odds=math.inf)


@dataclass
class StoreyEvidence:
    """A storey's BIM side of the checks, prepared once (the likelihood field is the costly part)."""

    ids: list[str]
    xy: np.ndarray
    normals: np.ndarray
    heights: np.ndarray
    categories: list[str]
    walls: np.ndarray
    field_: LikelihoodField | None
    free: FreeSpace | None = None
    landmarks: LandmarkView | None = None  # the lidar landmarks (None: the storey has none)

    @staticmethod
    def of(storey: StoreyModel, cmap: ClassMap) -> StoreyEvidence:
        f = storey.camera_features  # what the camera must see (the lidar landmarks are not its)
        walls = np.array([[w.x1, w.y1, w.x2, w.y2] for w in storey.walls], dtype=float).reshape(-1, 4)
        lm = storey.lidar_landmarks
        landmarks = (
            LandmarkView(
                np.array([[x.x, x.y] for x in lm], dtype=float),
                np.array([[x.norm_x, x.norm_y] for x in lm], dtype=float),
                tuple(LANDMARK_CLASSES.canonical(x.category) for x in lm),
            )
            if lm
            else None
        )
        return StoreyEvidence(
            [x.id for x in f],
            np.array([[x.x, x.y] for x in f], dtype=float).reshape(-1, 2),
            np.array([[x.norm_x, x.norm_y] for x in f], dtype=float).reshape(-1, 2),
            np.array([x.height for x in f], dtype=float),
            [cmap.canonical(x.category) for x in f],
            walls,
            likelihood_field(storey.grid) if storey.grid is not None else None,
            FreeSpace(storey.grid, VerificationParams().path_margin) if storey.grid is not None else None,
            landmarks,
        )


@dataclass
class PathEvidence:
    """The robot's side: odom poses of the images, every sighting, and the recent scans."""

    image_poses: list[Pose2D] = field(default_factory=list)
    image_travel: list[float] = field(default_factory=list)  # odometry distance at each image, m
    scans: list[ScanSample] = field(default_factory=list)
    scan_travel: list[float] = field(default_factory=list)
    # one scan every TRACK_STEP_M of travel over the last TRACK_KEPT_M: the lidar along the path
    track: list[ScanSample] = field(default_factory=list)
    track_travel: list[float] = field(default_factory=list)
    track_raw: list[ScanSample] = field(default_factory=list)  # the track's scans with every beam
    latest_raw: ScanSample | None = None  # the newest scan with every beam

    def recent(self, window_m: float, scan_window_m: float) -> tuple[list[Pose2D], list[ScanSample]]:
        now = max(
            self.image_travel[-1] if self.image_travel else 0.0,
            self.scan_travel[-1] if self.scan_travel else 0.0,
        )
        poses = [p for p, d in zip(self.image_poses, self.image_travel, strict=True) if now - d <= window_m]
        scans = [s for s, d in zip(self.scans, self.scan_travel, strict=True) if now - d <= scan_window_m]
        return poses, scans[-MAX_SCANS:]

    def add_image(self, odom: Pose2D, travel: float) -> None:
        self.image_poses.append(odom)
        self.image_travel.append(travel)

    def add_scan(
        self, odom: Pose2D, travel: float, angles: np.ndarray, ranges: np.ndarray, range_max: float
    ) -> None:
        raw = ScanSample(odom, np.asarray(angles), np.asarray(ranges), range_max)
        self.latest_raw = raw
        self.scans.append(raw.thinned(SCAN_BEAM_STEP))
        self.scan_travel.append(travel)
        if len(self.scans) > 4 * MAX_SCANS:
            del self.scans[: -2 * MAX_SCANS]
            del self.scan_travel[: -2 * MAX_SCANS]
        if not self.track_travel or travel - self.track_travel[-1] >= TRACK_STEP_M:
            s = self.scans[-1]
            k = TRACK_BEAM_STEP
            self.track.append(s.thinned(k))
            self.track_raw.append(raw)
            self.track_travel.append(travel)
            old = next((i for i, d in enumerate(self.track_travel) if travel - d <= TRACK_KEPT_M), 0)
            if old:
                del self.track[:old]
                del self.track_raw[:old]
                del self.track_travel[:old]

    def along(self, track_m: float, raw: bool = False) -> tuple[list[ScanSample], list[float]]:
        """The scans kept for the lidar along the path, over the last ``track_m`` of travel (``raw``:
        with every beam, else every :data:`TRACK_BEAM_STEP` th of :data:`SCAN_BEAM_STEP`)."""
        if not self.track_travel:
            return [], []
        now = self.track_travel[-1]
        first = next(i for i, d in enumerate(self.track_travel) if now - d <= track_m)
        return (self.track_raw if raw else self.track)[first:], self.track_travel[first:]

    @staticmethod
    def of_log(log: DetectionLog) -> PathEvidence:
        """The images' odom poses and the scans (at the latest odom pose before each) of a log."""
        *_, (path, _, _) = PathEvidence.growing(log)
        return path

    @staticmethod
    def growing(log: DetectionLog) -> Iterator[tuple[PathEvidence, float, float]]:
        """The path of a log as a session gathered it: before each odom record and at the end, the
        path so far (one object, growing), its odometry travel in m and the time of its last odom
        record."""
        out = PathEvidence()
        travel, t = 0.0, 0.0
        last: Pose2D | None = None
        for rec in log.records:
            if isinstance(rec, Odom):
                yield out, travel, t
                here = Pose2D(rec.x, rec.y, rec.yaw)
                if last is not None:
                    travel += last.distance_to(here)
                last, t = here, rec.t
            elif isinstance(rec, Scan) and last is not None:
                n = len(rec.ranges)
                angles = rec.angle_min + rec.angle_increment * np.arange(n)
                ranges = np.array([math.nan if r is None else r for r in rec.ranges], dtype=float)
                out.add_scan(last, travel, angles, ranges, rec.range_max)
            elif isinstance(rec, Detections):
                out.add_image(rec.pose, travel)
        yield out, travel, t


def verify_transform(
    transform: Pose2D,
    storey: StoreyEvidence,
    path: PathEvidence,
    sightings: Sequence[Sighting],
    view: CameraView,
    params: VerificationParams,
    seen_landmarks: Sequence[Located] | None = None,
    lines: float = 0.0,
) -> Verification:
    """The checks of :func:`initcli.core.verify.checks.verify_hypothesis` for ``transform`` (odom ->
    BIM) on ``storey``, with the images of the last ``PATH_WINDOW_M`` m and the scans of the last
    ``RECENT_SCANS_M`` m; the storey's lidar landmarks predicted from the path's scans of the last
    ``LANDMARK_WINDOW_M`` m against ``seen_landmarks``, the confirmed ones (odom frame; None: the
    lidar's landmarks are not tracked, so none is predicted either). ``lines`` > 0: the scans
    judged by their beams on straight lines that long (:func:`wall_beams`), as a registration on
    its wall beams placed them (the map lacks the furniture the other beams end on)."""
    poses, scans = path.recent(PATH_WINDOW_M, RECENT_SCANS_M)
    if lines > 0:
        raw, _ = path.along(RECENT_SCANS_M, raw=True)
        if raw:
            scans = [wall_beams(s, lines).thinned(SCAN_BEAM_STEP) for s in raw[-MAX_SCANS:]]
    recent_path, _ = path.recent(PATH_CHECK_M, 0.0)
    landmarks = None
    if storey.landmarks is not None and seen_landmarks is not None:
        swept, _ = path.along(LANDMARK_WINDOW_M)
        landmarks = LandmarkEvidence(
            storey.landmarks,
            [s.odom for s in swept],
            np.array([[f.x, f.y] for f in seen_landmarks], dtype=float).reshape(-1, 2),
            tuple(LANDMARK_CLASSES.canonical(f.cls) for f in seen_landmarks),
        )
    check = verify_hypothesis(
        transform,
        storey.ids,
        storey.xy,
        storey.normals,
        storey.heights,
        storey.categories,
        poses,
        np.array([[s.x, s.y] for s in sightings], dtype=float).reshape(-1, 2),
        [s.cls for s in sightings],
        view,
        storey.walls,
        scans,
        storey.field_,
        params,
        storey.free,
        recent_path,
        landmarks,
    )
    free = check.path_free
    if (
        free is not None
        and params.min_path_free - PATH_RETRY <= free < params.min_path_free
        and params.track_m > 0
    ):
        along = path_free_along(check.aligned_or(transform), storey, path, params)
        if along is not None and along > free:
            check = judge(replace(check, path_free=along), params)
    return check


def path_free_along(
    transform: Pose2D, storey: StoreyEvidence, path: PathEvidence, params: VerificationParams
) -> float | None:
    """The share of the last PATH_CHECK_M of the path on free BIM cells, each image pose placed by
    the transform of its window of the lidar along the path (:func:`path_track` from
    ``transform``), not by one transform for all: odometry drift over a long straight wall (a
    rotation of a degree or two) puts a right place's path through that wall (a car park's 30 m
    perimeter wall: 0.85 of the path on free cells). None without a map or scans."""
    track = path_track(transform, storey, path, params)
    if track is None or storey.free is None or not path.image_travel:
        return None
    now = path.image_travel[-1]
    placed = [
        track.at(d).apply(np.array([[p.x, p.y]]))[0]
        for p, d in zip(path.image_poses, path.image_travel, strict=True)
        if now - d <= PATH_CHECK_M
    ]
    return storey.free.share_free(np.array(placed)) if placed else None


def path_track(
    transform: Pose2D,
    storey: StoreyEvidence,
    path: PathEvidence,
    params: VerificationParams,
    wide: bool = False,
) -> PathTrack | None:
    """The lidar along the last ``track_m`` of the path for ``transform`` (odom -> BIM; start it from
    a verification's ``aligned`` transform): :func:`initcli.core.verify.checks.tracked_scan_fit` with
    the ``params``; ``wide``: the newest window searched over ``track_rival_xy`` /
    ``track_rival_yaw_deg`` first (a place about to be outranked). None without a map or scans, or
    with ``track_m`` 0."""
    scans, travel = path.along(params.track_m)
    if storey.field_ is None or not scans or params.track_m <= 0:
        return None
    return tracked_scan_fit(
        transform,
        scans,
        travel,
        storey.field_,
        params.scan_tolerance,
        params.track_window_m,
        params.track_search_xy,
        math.radians(params.track_search_yaw_deg),
        params.track_rival_xy if wide else 0.0,
        math.radians(params.track_rival_yaw_deg) if wide else 0.0,
    )


def track_transform(
    transform: Pose2D,
    storey: StoreyEvidence,
    path: PathEvidence,
    params: VerificationParams,
    wide: bool = False,
) -> np.ndarray:
    """The fits of :func:`path_track`, newest window first (empty without one)."""
    track = path_track(transform, storey, path, params, wide)
    return np.zeros(0) if track is None else track.fits


def verify_report(
    log: DetectionLog,
    site: Site,
    report: MatchReport,
    cmap: ClassMap,
    params: VerificationParams | None = None,
) -> list[Verification | None]:
    """The checks for each hypothesis of ``report`` (a ``bim-init match`` of ``log``), at the log's
    last odom pose, with the lidar along the path (``track_fit``); None for a hypothesis whose
    storey has no map or features."""
    return _check_report(log, site, report, cmap, params or VerificationParams())[0]


def verify_and_favour(
    log: DetectionLog,
    site: Site,
    report: MatchReport,
    cmap: ClassMap,
    params: VerificationParams | None = None,
) -> tuple[list[Verification | None], int | None]:
    """:func:`verify_report`'s checks and, with several hypotheses, the index of the one the lidar
    along the path plainly favours, one hypothesis per place, as a session decides it
    (:func:`initcli.core.verify.checks.track_favoured`); None when none stands out, the report
    lists fewer hypotheses than it counts or counts more than ``TRACK_HYPOTHESES`` (a session
    compares no more)."""
    params = params or VerificationParams()
    checks, path, storeys = _check_report(log, site, report, cmap, params)
    if path is None or report.n_hypotheses < 2:
        return checks, None
    return checks, _favoured(report, checks, path, storeys, params)


def _check_report(
    log: DetectionLog, site: Site, report: MatchReport, cmap: ClassMap, params: VerificationParams
) -> tuple[list[Verification | None], PathEvidence | None, dict[str, StoreyEvidence]]:
    """The checks of :func:`verify_report`, and the log's path and the storeys' evidence they were
    made from (no path without an odom pose)."""
    if report.odom_pose is None:
        return [None for _ in report.hypotheses], None, {}
    params = without_landmark_misses(params)  # check_loaded judges the claim with the landmarks' misses
    path = PathEvidence.of_log(log)
    sightings = sightings_from_log(log, cmap, report.options.edge_margin)
    view = CameraView(log.meta.camera, log.meta.camera_pose, report.options.min_depth)
    storeys: dict[str, StoreyEvidence] = {}
    out: list[Verification | None] = []
    for h in report.hypotheses:
        model = site.storeys.get(h.storey)
        if model is None or not model.features:
            out.append(None)
            continue
        if h.storey not in storeys:
            storeys[h.storey] = StoreyEvidence.of(model, cmap)
        transform = h.reported_pose * report.odom_pose.inverse()
        check = verify_transform(
            transform, storeys[h.storey], path, sightings, view, params, report.landmarks
        )
        track = track_transform(check.aligned_or(transform), storeys[h.storey], path, params)
        out.append(replace(check, track_fit=tuple(float(f) for f in track)) if len(track) else check)
    return out, path, storeys


def _favoured(
    report: MatchReport,
    checks: Sequence[Verification | None],
    path: PathEvidence,
    storeys: dict[str, StoreyEvidence],
    params: VerificationParams,
) -> int | None:
    """The favoured hypothesis of :func:`verify_and_favour`, from the evidence the checks used."""
    hs = report.hypotheses
    odom = report.odom_pose
    if odom is None or not report.n_hypotheses <= len(hs) <= TRACK_HYPOTHESES or params.track_m <= 0:
        return None
    candidates = [(i, checks[i]) for i in report.places()]
    if any(check is None or check.track_fit is None for _, check in candidates):
        return None

    def wide(k: int) -> np.ndarray:
        i, check = candidates[k]
        assert check is not None  # a checked hypothesis: its storey's evidence is in storeys
        h = hs[i]
        start = check.aligned_or(h.reported_pose * odom.inverse())
        return track_transform(start, storeys[h.storey], path, params, wide=True)

    found = track_favoured(
        [check is not None and check.passed for _, check in candidates],
        [hs[i].n_outliers for i, _ in candidates],
        [hs[i].n_inliers for i, _ in candidates],
        [np.asarray(check.track_fit if check is not None else ()) for _, check in candidates],
        wide,
        params,
    )
    return None if found is None else candidates[found][0]


def check_hypotheses(
    log_path: Path, site_path: Path, report: MatchReport, skip_bad: bool, shown: int
) -> list[Verification | None]:
    """Negative evidence, scan fit and the lidar along the path of each hypothesis
    (initcli.verify.evidence); with several hypotheses, the one the lidar along the path favours,
    matched on as many features as a session claims on (``min_claim_inliers``), makes the verdict
    unique (:func:`lidar_unique`), as a session would claim it. ``report`` lists up to
    ``TRACK_HYPOTHESES`` so that the verdict does not depend on ``--top``; it is cut to the
    ``shown`` first here, with the checks."""
    return check_loaded(read_log(log_path, skip_bad=skip_bad), load_site(site_path), report, shown)


def check_loaded(log: DetectionLog, site: Site, report: MatchReport, shown: int) -> list[Verification | None]:
    """:func:`check_hypotheses` on a log and a site (with its maps) already read."""
    params = VerificationParams()
    checks, favoured = verify_and_favour(log, site, report, site_class_map(site), params)
    claim = favoured if favoured is not None else 0 if report.decided_by == DECIDED_BY_PAPER else None
    if claim is not None and (check := checks[claim]) is not None:
        checks[claim] = judge(check, params)  # as a claim: its lidar landmarks' misses count now
    if (
        favoured is not None
        and report.weighted_inliers(report.hypotheses[favoured]) >= params.min_claim_inliers
        and ((c := checks[favoured]) is None or c.passed)
    ):
        checks = lidar_unique(report, checks, favoured)
    elif report.decided_by == DECIDED_BY_PAPER and checks and checks[0] is not None and not checks[0].passed:
        refuse_unique(report, checks[0])
    del report.hypotheses[shown:]
    report.options = replace(report.options, top=shown)
    return checks[:shown]


def refuse_unique(report: MatchReport, check: Verification) -> None:
    """Algorithm 1 left one place, but it fails the checks a session's claim must pass (the lidar
    does not fit the walls there, or it should have seen doors it did not): no pose is claimed,
    the verdict is ``no consistent match`` (``Verdict.NONE``), ``paper_verdict`` keeps ``unique match``."""
    report.paper_verdict = report.verdict
    report.decide(0)
    report.decided_by = None
    report.notes.append(
        "Algorithm 1's unique match fails the checks a session's claim must pass ("
        + "; ".join(check.reasons)
        + "): no pose is claimed; drive on and record more"
    )


def lidar_unique(
    report: MatchReport, checks: list[Verification | None], favoured: int
) -> list[Verification | None]:
    """Make ``report`` a unique match on its hypothesis ``favoured``, the one the lidar along the
    path plainly favours among several (:func:`verify_and_favour`; it passes the checks and
    outranks every other place): as a session claims it, so the log's verdict is the session's.
    That hypothesis goes first (ranks renumbered, the others kept below it as the places the lidar
    ruled out); ``paper_verdict`` keeps Algorithm 1's own. Returns ``checks`` in the new order."""
    order = [favoured, *(i for i in range(len(report.hypotheses)) if i != favoured)]
    was = report.hypotheses[favoured].rank
    report.hypotheses = [replace(report.hypotheses[i], rank=k) for k, i in enumerate(order, 1)]
    report.paper_verdict = report.verdict
    report.decide(1)
    report.decided_by = DECIDED_BY_LIDAR
    moved = f" (was {was})" if was != 1 else ""
    report.notes.append(
        f"unique by the lidar along the path: Algorithm 1 left {report.paper_verdict}; of these, the"
        f" scans along the path fit only hypothesis 1{moved}, as a session would claim it"
    )
    return [checks[i] for i in order]
