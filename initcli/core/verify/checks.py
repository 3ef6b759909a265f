"""Verification of a pose hypothesis against evidence Algorithm 1 does not use (beyond the paper).

A hypothesis is the transform ``T = pose_BIM * odom^-1`` that puts the robot's odometry frame into the
BIM frame (Eq. 10-13 give it at the last odom pose). Algorithm 1 only checks that the features that
*were* detected fit the BIM; it never asks about the features the hypothesis says the camera must
have seen but did not, nor whether the lidar agrees with the walls. The checks:

* **Negative evidence** -- every BIM feature that, under ``T``, stood in the camera's view (inside the
  image, within ``predict_range``, seen from its front side within ``predict_view_angle_deg`` of its
  normal, line of sight through the BIM's walls) in at least ``min_frames`` images of the path, yet no
  sighting of its category landed within ``match_radius`` of it. A few misses are normal on a site
  (doors not installed yet, a detector that misses); at a wrong place most predictions fail.
  The share test follows a binomial likelihood ratio: with a per-feature miss probability
  ``p_right`` at the right place and ``p_wrong`` at a wrong one, ``k`` misses of ``n`` favour the
  wrong place when ``k log(p_wrong/p_right) + (n-k) log((1-p_wrong)/(1-p_right)) > log_odds``.
* **Path in free space** -- the robot drove its odometry path, so under the right ``T`` that path
  (the last ``PATH_CHECK`` metres, as the images' poses) lies on free cells of the BIM map, within
  ``path_margin`` of one (odometry drift, as-built offsets). A hypothesis that puts the path through
  walls or outside the building is wrong.
* **Lidar landmarks missed** (beyond the paper) -- the same binomial rule for the storey's wall
  corners, column corners and openings: a landmark within ``landmark_range`` of ``landmark_min_views``
  of the path's scan poses, seen from within ``landmark_view_angle_deg`` of its normal (a corner's
  bisector: both its faces in sight) with no wall across, yet no confirmed lidar landmark of its
  category within ``landmark_match_radius``, is a miss, at ``landmark_p_right`` / ``landmark_p_wrong``.
  The camera's misses say nothing when the camera is blind; the lidar's still do.
* **Scan fit** -- the share of lidar beam end points of the recent scans, put into the BIM frame with
  ``T``, that land within ``scan_tolerance`` of an occupied map cell (the beam end-point model of the
  fine-tuning filter, Eq. 18, with no beam skipped). As-built deviations move walls by centimetres;
  a wrong corridor fits badly where the layouts differ.

Everything here is pure numpy on arrays; the session and ``bim-init match`` gather the inputs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from bimtools.site.records import FREE, OccupancyGrid
from initcli.core.features.visibility import CameraModel, FeatureArrays, sight_lines_blocked, visible
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D, poses_to_array, transform_poses
from initcli.core.lidar.scan_fit import BeamEnds, ScanSample, best_scan_alignment
from initcli.core.verify.params import VerificationParams

__all__ = [
    "CameraView",
    "FreeSpace",
    "LandmarkEvidence",
    "LandmarkView",
    "PathTrack",
    "RIVAL_MARGIN",
    "TRACK_HYPOTHESES",
    "Verification",
    "explained",
    "frames_in_view",
    "judge",
    "landmark_misses",
    "misses_reject",
    "outranks",
    "rival_search",
    "scans_in_view",
    "track_favoured",
    "track_outranks",
    "tracked_scan_fit",
    "trails",
    "verify_hypothesis",
]

RIVAL_MARGIN = 2  # more outliers than a noisy claim was found with that its rival search allows, at least
# several hypotheses are compared by the lidar along the path (track_favoured) up to this many
TRACK_HYPOTHESES = 12
WIDE_STEP_M, WIDE_STEP_DEG = 0.5, 5.0  # grid of tracked_scan_fit's widened first search
LANDMARK_FRONT = 0.1  # m: a landmark's sight line ends this far in front of it, along its normal


@dataclass(frozen=True)
class CameraView:
    """What the camera can see: intrinsics, mount, and the depth below which detections are not
    used (the detection filter's ``min_depth``)."""

    camera: CameraIntrinsics
    mount: CameraMount
    min_depth: float  # m


@dataclass(frozen=True)
class LandmarkView:
    """A storey's lidar landmarks (beyond the paper), BIM frame: positions (L, 2), unit normals into
    free space (L, 2; a corner's bisector) and canonical categories."""

    xy: np.ndarray
    normals: np.ndarray
    categories: tuple[str, ...]


@dataclass(frozen=True)
class LandmarkEvidence:
    """The lidar's side of the landmark check: the storey's landmarks, the odom poses of the path's
    scans and the confirmed lidar landmarks (odom frame positions (N, 2), canonical categories)."""

    landmarks: LandmarkView
    scan_poses: list[Pose2D]
    seen_xy: np.ndarray
    seen_categories: tuple[str, ...]


@dataclass(frozen=True)
class Verification:
    """The outcome of the checks for one hypothesis (reported in summary.json and match --json)."""

    predicted: int  # BIM features predicted in view
    missed_predictions: int  # ... of which never detected
    missed_ids: tuple[str, ...] = ()
    scan_fit: float | None = None  # None: no scans to judge by
    path_free: float | None = None  # share of the recent path on free BIM cells (None: no map)
    passed: bool = True
    reasons: tuple[str, ...] = field(default_factory=tuple)
    aligned: Pose2D | None = None  # the hypothesis (odom -> BIM) moved to where the scans fit best
    track_fit: tuple[float, ...] | None = None  # the lidar along the path, newest window first
    landmarks_predicted: int = 0  # BIM lidar landmarks predicted in the lidar's view ...
    landmarks_missed: int = 0  # ... of which no confirmed lidar landmark was near

    def aligned_or(self, transform: Pose2D) -> Pose2D:
        """Where the recent scans fit best (``aligned``), or ``transform`` when they were not fitted:
        where the lidar along the path starts."""
        return self.aligned if self.aligned is not None else transform

    def as_dict(self) -> dict[str, object]:
        doc: dict[str, object] = {
            "predicted": self.predicted,
            "missed_predictions": self.missed_predictions,
            "missed_ids": list(self.missed_ids),
            "scan_fit": None if self.scan_fit is None else round(self.scan_fit, 4),
            "path_free": None if self.path_free is None else round(self.path_free, 4),
            "landmarks_predicted": self.landmarks_predicted,
            "landmarks_missed": self.landmarks_missed,
            "passed": self.passed,
            "reasons": list(self.reasons),
        }
        if self.track_fit is not None:
            doc["track_fit"] = [round(f, 4) for f in self.track_fit]
        return doc


def frames_in_view(
    feature_xy: np.ndarray,
    feature_normals: np.ndarray,
    feature_heights: np.ndarray,
    robot_poses: np.ndarray,
    view: CameraView,
    walls: np.ndarray,
    params: VerificationParams,
) -> np.ndarray:
    """Per BIM feature (F,), the number of ``robot_poses`` ((P, 3) rows x, y, yaw, BIM frame) whose
    image shows it (the camera model of :mod:`initcli.core.features.visibility` with the prediction's
    tighter limits)."""
    xy = np.asarray(feature_xy, dtype=float).reshape(-1, 2)
    poses = np.asarray(robot_poses, dtype=float).reshape(-1, 3)
    if len(xy) == 0 or len(poses) == 0:
        return np.zeros(len(xy), dtype=int)
    model = CameraModel(
        view.camera,
        view.mount,
        min_range=view.min_depth,
        max_range=params.predict_range,
        max_view_angle_deg=params.predict_view_angle_deg,
        margin=params.image_margin,
    )
    features = FeatureArrays(
        xy,
        np.asarray(feature_normals, dtype=float).reshape(-1, 2),
        np.asarray(feature_heights, dtype=float),
        (),
    )
    return np.asarray(
        visible(poses, features, np.asarray(walls, dtype=float).reshape(-1, 4), model).sum(axis=0)
    )


def explained(
    feature_xy: np.ndarray,
    feature_categories: list[str],
    sighting_xy: np.ndarray,
    sighting_categories: list[str],
    radius: float,
) -> np.ndarray:
    """Per BIM feature, is there a sighting of the same category within ``radius`` (both BIM frame)?"""
    xy = np.asarray(feature_xy, dtype=float).reshape(-1, 2)
    s = np.asarray(sighting_xy, dtype=float).reshape(-1, 2)
    out = np.zeros(len(xy), dtype=bool)
    if len(s) == 0 or len(xy) == 0:
        return out
    d = np.hypot(xy[:, None, 0] - s[None, :, 0], xy[:, None, 1] - s[None, :, 1])
    same = (
        np.array(feature_categories, dtype=object)[:, None]
        == np.array(sighting_categories, dtype=object)[None, :]
    )
    return np.asarray(((d <= radius) & same).any(axis=1))


def misses_reject(missed: int, predicted: int, params: VerificationParams, lidar: bool = False) -> bool:
    """The binomial likelihood-ratio test of the module docstring: do ``missed`` of ``predicted``
    favour a wrong place by more than ``exp(log_odds)`` to one (``lidar``: the landmarks' rates and
    odds)?"""
    if predicted <= 0:
        return False
    pr, pw = (params.landmark_p_right, params.landmark_p_wrong) if lidar else (params.p_right, params.p_wrong)
    odds = params.landmark_log_odds if lidar else params.log_odds
    llr = missed * math.log(pw / pr) + (predicted - missed) * math.log((1.0 - pw) / (1.0 - pr))
    return llr > odds


def scans_in_view(
    xy: np.ndarray,
    normals: np.ndarray,
    poses: np.ndarray,
    walls: np.ndarray,
    max_range: float,
    max_view_angle_deg: float,
) -> np.ndarray:
    """Per landmark (L,), the number of robot ``poses`` ((P, 3) rows x, y, yaw, BIM frame; the lidar
    at the robot's centre, all round) from which the lidar sees it: within ``max_range``, from within
    ``max_view_angle_deg`` of its normal, with no wall across the sight line to a point
    ``LANDMARK_FRONT`` in front of it (a corner lies on the walls' faces)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    normals = np.asarray(normals, dtype=float).reshape(-1, 2)
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    if len(xy) == 0 or len(poses) == 0:
        return np.zeros(len(xy), dtype=int)
    to_robot = poses[:, None, 0:2] - xy[None, :, :]  # (P, L, 2)
    dist = np.hypot(to_robot[..., 0], to_robot[..., 1])
    cos_view = np.einsum("plk,lk->pl", to_robot, normals) / np.maximum(dist, 1e-12)
    facing = cos_view >= math.cos(math.radians(max_view_angle_deg))
    ok = (dist <= max_range) & (dist >= LANDMARK_FRONT) & facing
    pp, ll = np.nonzero(ok)
    walls = np.asarray(walls, dtype=float).reshape(-1, 4)
    if len(pp) and len(walls):
        blocked = sight_lines_blocked(poses[pp, 0:2], xy[ll] + LANDMARK_FRONT * normals[ll], walls)
        ok[pp[blocked], ll[blocked]] = False
    return np.asarray(ok.sum(axis=0))


def landmark_misses(
    transform: Pose2D, evidence: LandmarkEvidence, walls: np.ndarray, params: VerificationParams
) -> tuple[int, int]:
    """(predicted, missed): the storey's landmarks in the lidar's view from ``landmark_min_views``
    of the path's scan poses under ``transform`` (odom -> BIM; :func:`scans_in_view`), and those of
    them with no confirmed lidar landmark of their category within ``landmark_match_radius``."""
    lm = evidence.landmarks
    poses = transform_poses(transform, poses_to_array(evidence.scan_poses))
    views = scans_in_view(
        lm.xy, lm.normals, poses, walls, params.landmark_range, params.landmark_view_angle_deg
    )
    predicted = views >= params.landmark_min_views
    seen_bim = transform.apply(np.asarray(evidence.seen_xy, dtype=float).reshape(-1, 2))
    seen = explained(
        lm.xy, list(lm.categories), seen_bim, list(evidence.seen_categories), params.landmark_match_radius
    )
    return int(predicted.sum()), int((predicted & ~seen).sum())


class FreeSpace:
    """The BIM map's free cells, grown by a margin, for the path check."""

    def __init__(self, grid: OccupancyGrid, margin: float) -> None:
        free = (grid.cells == FREE).astype(np.uint8)
        k = max(1, int(round(margin / grid.resolution)))
        self.mask = cv2.dilate(free, np.ones((2 * k + 1, 2 * k + 1), np.uint8)) > 0
        self.grid = grid

    def share_free(self, xy: np.ndarray) -> float:
        """Share of the points (N, 2) on grown free cells (points off the map are not free)."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        if len(xy) == 0:
            return 1.0
        row, col = self.grid.world_to_cell(xy[:, 0], xy[:, 1])
        inside = (row >= 0) & (row < self.mask.shape[0]) & (col >= 0) & (col < self.mask.shape[1])
        ok = np.zeros(len(xy), dtype=bool)
        ok[inside] = self.mask[row[inside], col[inside]]
        return float(ok.mean())


def rival_search(
    configured: int, claim_outliers: int, outliers_allowed: int, max_outliers: int, budget: int = 0
) -> int:
    """How many more outliers than the claim was found with a unique match must stay unique under.

    A match that needed outliers (``claim_outliers`` > 0), or was found only once the outlier
    budget grew past ``max_outliers``, is unique among the fewest-outlier explanations of noisy
    data; the true place may need more outliers (doors built off their place, posters): it must
    stay unique up to the ``budget`` that the matcher accepts as an explanation at all
    (``outlier_share`` of the features), and with at least RIVAL_MARGIN more allowed even there (a
    point-symmetric corridor with 40 % of its doors missing: the turned place explained the
    detections within the budget, the true one needed two outliers more). A match that explains every
    detection needs only the ``configured`` search (``rival_outliers``, 1 by default: on a site as
    built the true place can need an outlier that a place one door along does not; 0: none)."""
    noisy = claim_outliers > 0 or outliers_allowed > max_outliers
    found_with = max(outliers_allowed, max_outliers)
    return max(configured, max(RIVAL_MARGIN, budget - found_with) if noisy else 0)


def trails(outliers: int, other_outliers: int, params: VerificationParams) -> bool:
    """Does a place found with ``other_outliers`` need ``outrank_outliers`` more than one found with
    ``outliers`` (what ``outranks`` and the trailing lead of ``track_outranks`` ask)?"""
    return other_outliers >= outliers + params.outrank_outliers


def outranks(
    claim: Verification,
    claim_outliers: int,
    rival: Verification,
    rival_outliers: int,
    params: VerificationParams,
) -> bool:
    """Is the claim plainly the better explanation than a rival found with more outliers allowed?

    True for a rival that fails the checks, and for one that passes them with at least
    ``outrank_outliers`` more outliers *and* a scan fit at least ``outrank_scan_fit`` below the
    claim's (the rival's fit searched over its wider shifts). In 420 construction sessions of the
    three samples (``benchmarks/bench_claims.py``) no wrong-place claim beat the true place, found
    as its rival, by more than 0.01 in scan fit with one outlier fewer; right claims beat their
    credible rivals by up to 0.3. A claim with no scans to fit never outranks."""
    if not rival.passed:
        return True
    if claim.scan_fit is None or rival.scan_fit is None:
        return False
    return trails(claim_outliers, rival_outliers, params) and (
        rival.scan_fit <= claim.scan_fit - params.outrank_scan_fit
    )


@dataclass(frozen=True)
class PathTrack:
    """The lidar along the path (:func:`tracked_scan_fit`): per window of travel, newest first,
    its fit and the transform (odom -> BIM) that aligns it."""

    fits: np.ndarray
    transforms: tuple[Pose2D, ...]
    windows: tuple[int, ...]  # each window's number counted back from the newest scan
    newest: float  # m of travel at the newest scan
    window_m: float

    def at(self, travel: float) -> Pose2D:
        """The transform of the window holding ``travel`` (the oldest one for travel before it)."""
        k = int(max(self.newest - travel, 0.0) // self.window_m)
        i = int(np.searchsorted(np.asarray(self.windows), k, side="right")) - 1
        return self.transforms[max(i, 0)]


def tracked_scan_fit(
    transform: Pose2D,
    scans: list[ScanSample],
    travel: list[float],
    field_: LikelihoodField,
    tolerance: float,
    window_m: float,
    search_xy: float,
    search_yaw: float,
    first_xy: float = 0.0,
    first_yaw: float = 0.0,
) -> PathTrack | None:
    """The lidar's fit along the path, window by window, newest first (beyond the paper).

    ``scans`` (oldest first, ``travel`` the odometry distance at each) are cut into windows of
    ``window_m`` metres of travel counted back from the last scan. The newest window is aligned by
    :func:`best_scan_alignment` from ``transform`` (odom -> BIM), each older one from the alignment
    of the window after it, by a move of at most ``search_xy`` m and ``search_yaw`` rad (a coarse
    grid, then a finer one around its best): odometry drift is followed back along the path, a
    place one corridor bay or one turn away is not. Returns each window's fit (share of beams within
    ``tolerance`` of a mapped wall). The scans a hypothesis explains at every window lie where it
    says; a place that only the recent scans support (a periodic corridor seen from its middle)
    fits badly where the path turned into a corridor end or a lobby. Each window's transform places
    the path driven in it despite odometry drift. ``first_xy`` / ``first_yaw`` widen the search of
    the newest window (a grid of WIDE_STEP_M and WIDE_STEP_DEG steps first): a
    place found imprecisely (doors built off their place) is compared where its scans fit best.
    None when there is no scan."""
    if not scans:
        return None
    now = travel[-1]
    windows: dict[int, list[ScanSample]] = {}
    for scan, d in zip(scans, travel, strict=True):
        windows.setdefault(int((now - d) // window_m), []).append(scan)
    fits, transforms = [], []
    current = transform
    fine_xy, fine_yaw = search_xy / 2.0, search_yaw / 4.0
    for k in sorted(windows):
        window = BeamEnds.of(windows[k])
        if k == min(windows) and (first_xy > 0 or first_yaw > 0):
            wide = best_scan_alignment(
                current,
                window,
                field_,
                tolerance,
                first_xy,
                first_yaw,
                2 * math.ceil(first_xy / WIDE_STEP_M) + 1,
                WIDE_STEP_DEG,
            )
            assert wide is not None
            current = wide[1]
        coarse = best_scan_alignment(
            current, window, field_, tolerance, search_xy, search_yaw, 3, math.degrees(search_yaw) / 2.0
        )
        assert coarse is not None
        found = best_scan_alignment(
            coarse[1], window, field_, tolerance, fine_xy, fine_yaw, 3, math.degrees(fine_yaw)
        )
        assert found is not None
        fit, current = found
        fits.append(fit)
        transforms.append(current)
    return PathTrack(np.array(fits), tuple(transforms), tuple(sorted(windows)), now, window_m)


def track_outranks(
    track: np.ndarray, other: np.ndarray, params: VerificationParams, trailing: bool = False
) -> bool:
    """Do the scans along the path plainly favour ``track``'s hypothesis over ``other``'s (both from
    :func:`tracked_scan_fit` fits over the same scans)? True when they share ``min_track_windows``
    windows or more, ``track`` fits none of its windows below ``min_track_fit``, fits some window at
    least ``track_lead`` better than ``other`` (``trailing``: the other needs ``outrank_outliers``
    more outliers, ``track_lead_trailing`` is enough) and no window more than ``track_slack`` worse.
    In 420 construction sessions of the three samples (``benchmarks/bench_claims.py`` at cfb9853:
    5,756 pairs of a right place passing the recent checks and a wrong one, 3,551 the other way
    round, the place to be outranked also searched wide), the right place outranked the wrong one
    3,096 times, the wrong one the right one 3 times, each on a single window at the initial look;
    with a trailing lead of 0.1 over a place with more outliers, 79 such wrong-right pairs, none.
    With these rules, at 4ba9f3d: right over wrong 2,995 of 5,689 pairs, wrong over right 2 of
    3,608, both against a hypothesis 1.8 m and 29 degrees off the truth in a set whose 0.2 m one
    held its own (CHANGELOG.md, "Which checks matter")."""
    n = min(len(track), len(other))
    if n == 0 or n < params.min_track_windows or float(np.min(track)) < params.min_track_fit:
        return False
    lead = track[:n] - other[:n]
    need = params.track_lead_trailing if trailing else params.track_lead
    return float(lead.max()) >= need and float(-lead.min()) <= params.track_slack


def track_favoured(
    passed: Sequence[bool],
    outliers: Sequence[int],
    inliers: Sequence[int],
    tracks: Sequence[np.ndarray],
    wide: Callable[[int], np.ndarray],
    params: VerificationParams,
) -> int | None:
    """Of several hypotheses, one per place (whether each ``passed`` the checks a claim must pass,
    their ``outliers``, matched ``inliers`` and lidar along the path ``tracks``), the index of the
    one the scans of the path plainly favour (beyond the paper): the one that passes the checks
    with ``min_claim_inliers`` matches and no more outliers than any hypothesis, and
    ``track_outranks`` every other, each other also with its newest window searched wide
    (``wide(i)``: the track of hypothesis ``i`` so searched, asked for only then; one with
    ``outrank_outliers`` more outliers is outranked by the trailing lead). A hypothesis that fails
    the recent checks must be outranked too: it may be the true place found imprecisely (1.5 m
    off, its recent scans fit 0.53) beside a turned place of a symmetric corridor that fits them
    well (block_b, hoardings twice the construction profile, seed 5). None when no hypothesis stands
    out so."""
    n = len(tracks)
    if n < 2 or not any(passed):
        return None
    fewest = min(outliers)

    def beats(i: int, j: int, track: np.ndarray) -> bool:
        return track_outranks(tracks[i], track, params, trails(outliers[i], outliers[j], params))

    winners = [
        i
        for i in range(n)
        if passed[i]
        and outliers[i] == fewest
        and inliers[i] >= params.min_claim_inliers
        and all(beats(i, j, tracks[j]) for j in range(n) if j != i)
    ]
    if len(winners) != 1:
        return None
    best = winners[0]
    if all(beats(best, j, wide(j)) for j in range(n) if j != best):
        return best
    return None


def verify_hypothesis(
    transform: Pose2D,
    feature_ids: list[str],
    feature_xy: np.ndarray,
    feature_normals: np.ndarray,
    feature_heights: np.ndarray,
    feature_categories: list[str],
    camera_odom_poses: list[Pose2D],
    sighting_odom_xy: np.ndarray,
    sighting_categories: list[str],
    view: CameraView,
    walls: np.ndarray,
    scans: list[ScanSample],
    field_: LikelihoodField | None,
    params: VerificationParams,
    free: FreeSpace | None = None,
    path_odom: list[Pose2D] | None = None,
    landmarks: LandmarkEvidence | None = None,
) -> Verification:
    """Both checks for the hypothesis ``transform`` (odom -> BIM) on one storey's BIM features.

    ``camera_odom_poses`` are the robot's odom poses at the images the detector ran on;
    ``sighting_odom_xy`` every detection's odom point (Eq. 1-2), confirmed or not."""
    poses = transform_poses(transform, poses_to_array(camera_odom_poses))
    in_view = frames_in_view(feature_xy, feature_normals, feature_heights, poses, view, walls, params)
    predicted = in_view >= params.min_frames
    s_bim = transform.apply(np.asarray(sighting_odom_xy, dtype=float).reshape(-1, 2))
    seen = explained(feature_xy, feature_categories, s_bim, sighting_categories, params.match_radius)
    missed_mask = predicted & ~seen
    n_pred, n_miss = int(predicted.sum()), int(missed_mask.sum())
    found = (
        best_scan_alignment(
            transform,
            scans,
            field_,
            params.scan_tolerance,
            params.scan_search_xy,
            math.radians(params.scan_search_yaw_deg),
        )
        if field_ is not None
        else None
    )
    fit, aligned = (None, None) if found is None else found
    path_free = None
    if free is not None and path_odom:
        path_free = free.share_free(transform.apply(np.array([[p.x, p.y] for p in path_odom])))
    lm_pred, lm_miss = (0, 0) if landmarks is None else landmark_misses(transform, landmarks, walls, params)
    return judge(
        Verification(
            predicted=n_pred,
            missed_predictions=n_miss,
            missed_ids=tuple(feature_ids[i] for i in np.flatnonzero(missed_mask)),
            scan_fit=fit,
            path_free=path_free,
            aligned=aligned,
            landmarks_predicted=lm_pred,
            landmarks_missed=lm_miss,
        ),
        params,
    )


def judge(check: Verification, params: VerificationParams) -> Verification:
    """``check`` with ``passed`` and ``reasons`` set from its evidence: the path in free space, the
    misses (binomial rule) and the scan fit, each against its threshold (all pass when the checks
    are off)."""
    reasons = []
    path_free, n_miss, n_pred, fit = (
        check.path_free,
        check.missed_predictions,
        check.predicted,
        check.scan_fit,
    )
    if path_free is not None and path_free < params.min_path_free:
        reasons.append(f"the path runs through walls or outside ({path_free:.2f} of it on free space)")
    if misses_reject(n_miss, n_pred, params):
        reasons.append(f"{n_miss} of {n_pred} BIM features in view were never detected")
    if misses_reject(check.landmarks_missed, check.landmarks_predicted, params, lidar=True):
        reasons.append(
            f"{check.landmarks_missed} of {check.landmarks_predicted} lidar landmarks in view were never seen"
        )
    if fit is not None and fit < params.min_scan_fit:
        reasons.append(f"lidar fits the BIM walls poorly ({fit:.2f} < {params.min_scan_fit:.2f})")
    return replace(check, passed=not reasons or not params.enabled, reasons=tuple(reasons))
