"""Negative evidence and scan fit of a pose hypothesis (initcli.core.verify.checks)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D, poses_to_array
from initcli.core.lidar.scan_fit import ScanSample, best_scan_alignment
from initcli.core.verify.checks import (
    CameraView,
    LandmarkEvidence,
    LandmarkView,
    Verification,
    VerificationParams,
    explained,
    frames_in_view,
    landmark_misses,
    misses_reject,
    outranks,
    rival_search,
    scans_in_view,
    track_favoured,
    track_outranks,
    tracked_scan_fit,
    verify_hypothesis,
)
from tests.helpers import walls_grid

VIEW = CameraView(
    CameraIntrinsics(600.0, 600.0, 320.0, 240.0, 640, 480), CameraMount(0.2, 0.0, 1.0, 0, 0, 0), min_depth=0.5
)
# A corridor 2 m wide along +x (y in [0, 2]); doors on the north wall (y = 2) every 4 m, facing -y.
DOORS_X = np.arange(2.0, 40.0, 4.0)
DOOR_XY = np.column_stack([DOORS_X, np.full(len(DOORS_X), 2.0)])
DOOR_N = np.tile([0.0, -1.0], (len(DOORS_X), 1))
DOOR_H = np.full(len(DOORS_X), 2.1)
WALLS = np.array([[-1.0, 0.0, 41.0, 0.0], [-1.0, 2.0, 41.0, 2.0]])


def path_along(x0: float, x1: float, yaw: float = math.radians(60.0)) -> list[Pose2D]:
    """Robot poses along the corridor centre line, the camera turned toward the north wall."""
    return [Pose2D(float(x), 1.0, yaw) for x in np.arange(x0, x1, 0.25)]


def test_frames_in_view_counts_only_features_in_front_and_in_range() -> None:
    poses = poses_to_array(path_along(0.0, 10.0))
    counts = frames_in_view(DOOR_XY, DOOR_N, DOOR_H, poses, VIEW, WALLS, VerificationParams())
    assert counts[0] > 0 and counts[1] > 0  # doors at x = 2 and 6 pass the camera
    assert counts[-1] == 0  # the door at x = 38 is far ahead
    behind = frames_in_view(DOOR_XY, -DOOR_N, DOOR_H, poses, VIEW, WALLS, VerificationParams())
    assert behind.sum() == 0  # a door seen from its back side is never predicted


def test_a_wall_between_camera_and_feature_hides_it() -> None:
    poses = poses_to_array(path_along(0.0, 4.0))
    clear = frames_in_view(DOOR_XY[:1], DOOR_N[:1], DOOR_H[:1], poses, VIEW, WALLS, VerificationParams())
    screen = np.vstack([WALLS, [[0.0, 1.5, 5.0, 1.5]]])  # a hoarding along the corridor
    hidden = frames_in_view(DOOR_XY[:1], DOOR_N[:1], DOOR_H[:1], poses, VIEW, screen, VerificationParams())
    assert clear[0] > 0 and hidden[0] == 0


def test_explained_needs_the_same_category_nearby() -> None:
    feats = np.array([[0.0, 0.0], [5.0, 0.0]])
    sightings = np.array([[0.4, 0.3], [5.0, 0.2]])
    assert explained(feats, ["door", "lift"], sightings, ["door", "door"], 1.0).tolist() == [True, False]
    assert explained(feats, ["door", "lift"], np.zeros((0, 2)), [], 1.0).tolist() == [False, False]


def test_binomial_rule_tolerates_some_misses_but_not_most() -> None:
    p = VerificationParams()
    assert not misses_reject(0, 0, p)
    assert not misses_reject(3, 10, p)  # 30 %: doors not installed, detector misses
    assert misses_reject(9, 10, p)
    assert misses_reject(3, 3, p)
    assert not misses_reject(2, 3, p)


def test_negative_evidence_rejects_the_place_where_doors_should_have_been_seen() -> None:
    odom_path = path_along(0.0, 20.0)  # odometry frame = BIM frame for the right hypothesis
    seen = DOOR_XY[DOORS_X < 20.0] + np.array([0.0, -0.3])  # every door passed was detected
    args = dict(
        feature_ids=[f"d{i}" for i in range(len(DOORS_X))],
        feature_xy=DOOR_XY,
        feature_normals=DOOR_N,
        feature_heights=DOOR_H,
        feature_categories=["door"] * len(DOORS_X),
        camera_odom_poses=odom_path,
        sighting_odom_xy=seen,
        sighting_categories=["door"] * len(seen),
        view=VIEW,
        walls=WALLS,
        scans=[],
        field_=None,
        params=VerificationParams(),
    )
    right = verify_hypothesis(Pose2D.identity(), **args)  # type: ignore[arg-type]
    assert right.passed and right.predicted >= 4 and right.missed_predictions == 0
    # A wrong hypothesis 2 m along the corridor: every door it predicts lies between the detected ones.
    wrong = verify_hypothesis(Pose2D(2.0, 0.0, 0.0), **args)  # type: ignore[arg-type]
    assert not wrong.passed
    assert wrong.missed_predictions == wrong.predicted >= 4
    assert "never detected" in wrong.reasons[0]


# Niches on the north wall of the corridor every 4 m: each a concave corner pair at its mouth's ends
# (bisectors into the corridor, turned 45 degrees) -- the lidar landmarks of a plan that repeats.
NICHE_X = np.arange(4.0, 40.0, 4.0)
CORNER_XY = np.vstack([np.column_stack([NICHE_X + dx, np.full(len(NICHE_X), 2.0)]) for dx in (-0.5, 0.5)])
CORNER_N = np.vstack([np.tile([s * math.sqrt(0.5), -math.sqrt(0.5)], (len(NICHE_X), 1)) for s in (1.0, -1.0)])
CORNERS = LandmarkView(CORNER_XY, CORNER_N, ("concavecorner",) * len(CORNER_XY))


def landmark_evidence(seen: np.ndarray, path: list[Pose2D]) -> LandmarkEvidence:
    return LandmarkEvidence(CORNERS, path, seen, ("concavecorner",) * len(seen))


def test_a_landmark_is_in_the_lidars_view_in_range_facing_and_unblocked() -> None:
    poses = poses_to_array([Pose2D(x, 1.0, 0.0) for x in np.arange(0.0, 12.0, 0.5)])
    views = scans_in_view(CORNER_XY, CORNER_N, poses, WALLS, 5.0, 40.0)
    first = int(np.flatnonzero(NICHE_X == 4.0)[0])
    assert views[first] > 0  # the niche at x = 4, passed
    assert views[int(np.flatnonzero(NICHE_X == 36.0)[0])] == 0  # out of range
    assert scans_in_view(CORNER_XY, -CORNER_N, poses, WALLS, 5.0, 40.0).sum() == 0  # behind the wall
    screen = np.vstack([WALLS, [[-1.0, 1.6, 18.0, 1.6]]])  # a hoarding along the north wall
    assert scans_in_view(CORNER_XY, CORNER_N, poses, screen, 5.0, 40.0).sum() == 0
    narrow = scans_in_view(CORNER_XY, CORNER_N, poses, WALLS, 5.0, 10.0)
    assert narrow[first] < views[first]  # fewer poses within 10 degrees of the bisector


def test_landmarks_missed_reject_a_place_a_bay_off_however_blind_the_camera() -> None:
    path = [Pose2D(float(x), 1.0, 0.0) for x in np.arange(0.0, 20.0, 0.5)]
    seen = CORNER_XY[CORNER_XY[:, 0] < 22.0] + 0.05  # every corner passed was confirmed
    params = VerificationParams()
    predicted, missed = landmark_misses(Pose2D.identity(), landmark_evidence(seen, path), WALLS, params)
    assert predicted >= 6 and missed == 0
    # 2 m along: every corner predicted lies half a bay from the confirmed ones
    predicted, missed = landmark_misses(Pose2D(2.0, 0.0, 0.0), landmark_evidence(seen, path), WALLS, params)
    assert missed == predicted >= 6
    args = dict(
        feature_ids=[],
        feature_xy=np.zeros((0, 2)),
        feature_normals=np.zeros((0, 2)),
        feature_heights=np.zeros(0),
        feature_categories=[],
        camera_odom_poses=path,
        sighting_odom_xy=np.zeros((0, 2)),
        sighting_categories=[],
        view=VIEW,
        walls=WALLS,
        scans=[],
        field_=None,
        params=dataclasses.replace(params, log_odds=math.inf),  # a blind camera's claim_params
    )
    right = verify_hypothesis(Pose2D.identity(), landmarks=landmark_evidence(seen, path), **args)  # type: ignore[arg-type]
    wrong = verify_hypothesis(Pose2D(2.0, 0.0, 0.0), landmarks=landmark_evidence(seen, path), **args)  # type: ignore[arg-type]
    assert right.passed and right.landmarks_predicted >= 6
    assert not wrong.passed and "lidar landmarks in view were never seen" in wrong.reasons[0]
    assert wrong.as_dict()["landmarks_missed"] == wrong.landmarks_missed
    # the same category only: corners confirmed as openings explain nothing
    other = LandmarkEvidence(CORNERS, path, seen, ("opening",) * len(seen))
    assert landmark_misses(Pose2D.identity(), other, WALLS, params)[1] >= 6


def test_the_landmark_rule_has_its_own_rates() -> None:
    p = VerificationParams()
    assert not misses_reject(4, 10, p, lidar=True)  # clutter hides corners at the right place too
    assert misses_reject(10, 10, p, lidar=True)
    assert misses_reject(3, 3, p) and not misses_reject(3, 3, p, lidar=True)  # corners: more misses
    loose = dataclasses.replace(p, landmark_log_odds=50.0)
    assert not misses_reject(10, 10, loose, lidar=True) and misses_reject(10, 10, loose)


def corridor_grid() -> OccupancyGrid:
    res = 0.05
    cells = np.full((80, 900), FREE, dtype=np.uint8)  # x in [-1, 44), y in [-1, 3)
    for y in (0.0, 2.0):
        row = 80 - 1 - int(round((y + 1.0) / res))
        cells[row, :] = OCCUPIED
    return OccupancyGrid(cells, res, (-1.0, -1.0, 0.0))


def corridor_scan(pose: Pose2D) -> ScanSample:
    """A 90-beam scan from ``pose`` in the corridor (walls at y = 0 and 2), ranges to the walls."""
    angles = np.linspace(-math.pi, math.pi, 90, endpoint=False)
    heading = pose.yaw + angles
    sin = np.sin(heading)
    with np.errstate(divide="ignore"):
        r = np.where(sin > 1e-6, (2.0 - pose.y) / sin, np.where(sin < -1e-6, -pose.y / sin, np.inf))
    ranges = np.where(r < 10.0, r, 20.0)
    return ScanSample(pose, angles, ranges, 20.0)


def path_scan_fit(
    transform: Pose2D, scans: list[ScanSample], field: LikelihoodField, tolerance: float, **search: float
) -> float | None:
    """The fit of :func:`best_scan_alignment` alone (None: no scans)."""
    found = best_scan_alignment(transform, scans, field, tolerance, **search)
    return None if found is None else found[0]


def test_scan_fit_is_high_at_the_right_transform_and_low_when_turned() -> None:
    field = LikelihoodField(corridor_grid())
    scans = [corridor_scan(Pose2D(float(x), 0.9, 0.3)) for x in (5.0, 6.0, 7.0)]
    right = path_scan_fit(Pose2D.identity(), scans, field, 0.25)
    turned = path_scan_fit(
        Pose2D(7.0, 0.9, math.pi / 2) * Pose2D(7.0, 0.9, 0.0).inverse(), scans, field, 0.25
    )
    assert right is not None and right > 0.95
    assert turned is not None and turned < 0.5
    # A pose 0.3 m off is found by the local search.
    off = Pose2D(0.0, 0.3, 0.0)
    assert path_scan_fit(off, scans, field, 0.1) < 0.5  # type: ignore[operator]
    assert path_scan_fit(off, scans, field, 0.1, search_xy=0.3) > 0.95  # type: ignore[operator]
    assert path_scan_fit(Pose2D.identity(), [], field, 0.25) is None


def test_the_path_must_lie_in_free_space() -> None:
    from bimtools.site.records import UNKNOWN
    from initcli.core.verify.checks import FreeSpace

    grid = corridor_grid()
    cells = grid.cells.copy()
    rows_y = grid.origin[1] + (cells.shape[0] - 1 - np.arange(cells.shape[0]) + 0.5) * grid.resolution
    cells[(rows_y < 0.0) | (rows_y > 2.0)] = UNKNOWN  # outside the corridor: not free space
    free = FreeSpace(OccupancyGrid(cells, grid.resolution, grid.origin), 0.3)
    along = np.column_stack([np.linspace(1.0, 30.0, 60), np.full(60, 1.0)])  # the corridor's centre line
    assert free.share_free(along) == 1.0
    across = np.column_stack([np.full(60, 10.0), np.linspace(-0.9, 2.9, 60)])  # through both walls
    assert free.share_free(across) < 0.9
    outside = along + np.array([0.0, 40.0])
    assert free.share_free(outside) == 0.0


def test_the_best_alignment_corrects_a_turned_and_shifted_coarse_pose() -> None:
    """A coarse pose 9 degrees turned and 0.3 m off the corridor's centre line: the search brings it
    back to where the scans fit (the seed fine tuning starts from)."""
    field = LikelihoodField(corridor_grid())
    scans = [corridor_scan(Pose2D(float(x), 0.9, 0.0)) for x in (20.0, 21.0, 22.0)]
    last = scans[-1].odom
    wrong = Pose2D(last.x, last.y + 0.3, math.radians(9.0)) * last.inverse()
    found = best_scan_alignment(wrong, scans, field, 0.1, 0.3, math.radians(12.0))
    assert found is not None
    fit, aligned = found
    assert fit > 0.9 > path_scan_fit(wrong, scans, field, 0.1)  # type: ignore[operator]
    here = aligned * last
    assert abs(here.y - last.y) < 0.1 and abs(math.degrees(here.yaw)) < 1.5
    assert best_scan_alignment(Pose2D.identity(), [], field, 0.1, 0.3, 0.2) is None


def test_the_best_alignment_equals_scoring_each_move_scan_by_scan() -> None:
    """The vectorised search against its definition: every move of the 5 x 5 x turns grid scored by
    :func:`scan_fit` on each scan, the mean over scans, the first best in order of nearness."""
    from initcli.core.filters.particle_filter import scan_fit

    field = LikelihoodField(corridor_grid())
    rng = np.random.default_rng(5)
    scans = [
        corridor_scan(Pose2D(float(x), 0.9 + 0.1 * rng.normal(), 0.2 * rng.normal())) for x in (8, 9, 10)
    ]
    scans[1].ranges[::7] = np.inf  # invalid beams are left out of a scan's share
    last = scans[-1].odom
    coarse = Pose2D(last.x + 0.2, last.y - 0.1, math.radians(7.0)) * last.inverse()
    search_xy, search_yaw = 0.3, math.radians(12.0)
    found = best_scan_alignment(coarse, scans, field, 0.1, search_xy, search_yaw)
    assert found is not None
    here = coarse * last
    shifts = np.linspace(-search_xy, search_xy, 5)
    turns = np.linspace(-search_yaw, search_yaw, 9)
    moves = sorted(
        ((float(a), float(dx), float(dy)) for a in turns for dx in shifts for dy in shifts),
        key=lambda m: abs(m[0]) / search_yaw + math.hypot(m[1], m[2]) / search_xy,
    )
    best = (-1.0, coarse)
    for dyaw, dx, dy in moves:
        moved = Pose2D(here.x + dx, here.y + dy, here.yaw + dyaw) * last.inverse()
        fit = float(
            np.mean([scan_fit(moved * s.odom, s.angles, s.ranges, s.range_max, field, 0.1) for s in scans])
        )
        if fit > best[0]:
            best = (fit, moved)
    assert found[0] == pytest.approx(best[0], abs=1e-9)
    assert found[1].distance_to(best[1]) < 1e-9 and found[1].yaw_error(best[1]) < 1e-9


@pytest.mark.parametrize(
    ("configured", "claim_outliers", "allowed", "expected"),
    [
        (0, 0, 1, 0),  # every detection explained: claimed without a rival search
        (0, 1, 1, 2),  # it needed an outlier: the true place may need two more
        (0, 0, 3, 2),  # found only once the budget grew past max_outliers (1)
        (3, 0, 1, 3),  # rival_outliers set by the user wins when larger
    ],
)
def test_a_noisy_claim_must_stay_unique_with_two_more_outliers(
    configured: int, claim_outliers: int, allowed: int, expected: int
) -> None:
    assert rival_search(configured, claim_outliers, allowed, max_outliers=1) == expected


def test_a_noisy_claim_must_stay_unique_up_to_the_outlier_budget() -> None:
    # 12 features, outlier_share 0.34: the matcher accepts 4 outliers as an explanation, so a claim
    # with one outlier must have no rival with up to 4 (3 more than the 1 it was found with).
    assert rival_search(0, 1, 1, max_outliers=1, budget=4) == 3
    assert rival_search(0, 1, 1, max_outliers=1, budget=3) == 2
    assert rival_search(0, 3, 3, max_outliers=1, budget=3) == 2  # at the budget: still two more
    assert rival_search(0, 0, 1, max_outliers=1, budget=3) == 0  # nothing unexplained: no search


def _checked(fit: float | None, passed: bool = True) -> Verification:
    return Verification(predicted=4, missed_predictions=1, scan_fit=fit, passed=passed)


def test_a_rival_that_fails_the_checks_never_holds_a_claim_back() -> None:
    assert outranks(_checked(0.8), 3, _checked(0.99, passed=False), 0, VerificationParams())


@pytest.mark.parametrize(
    ("rival_outliers", "rival_fit", "expected"),
    [
        (2, 0.85, True),  # one outlier more and 0.05 less fit: outranked
        (4, 0.70, True),
        (1, 0.50, False),  # as few outliers as the claim: it holds its own however badly it fits
        (0, 0.50, False),
        (2, 0.86, False),  # fits within 0.05 of the claim: it holds its own
        (5, 0.95, False),
        (2, None, False),  # no scans to compare
    ],
)
def test_a_credible_rival_is_outranked_only_when_it_trails_in_outliers_and_scan_fit(
    rival_outliers: int, rival_fit: float | None, expected: bool
) -> None:
    assert outranks(_checked(0.9), 1, _checked(rival_fit), rival_outliers, VerificationParams()) is expected


def test_outranking_is_off_with_a_scan_fit_margin_of_one() -> None:
    params = VerificationParams(outrank_scan_fit=1.0)
    assert not outranks(_checked(1.0), 0, _checked(0.66), 5, params)
    assert not outranks(_checked(None), 0, _checked(0.66), 5, VerificationParams())


# -- the lidar along the path ----------------------------------------------------------------------
# An L of corridors 2 m wide: A along x (y in [0, 2], open far to the west), B along y (x in [40, 42])
# from A's east end. Seen from A's middle every place along A looks alike to a 12 m lidar; only the
# scans from B, where the robot came from, tell a place one bay along A from the right one.
ELL = np.array(
    [[-30.0, 0.0, 42.0, 0.0], [-30.0, 2.0, 40.0, 2.0], [40.0, 2.0, 40.0, 30.0], [42.0, 0.0, 42.0, 30.0]]
)


def ell_grid() -> OccupancyGrid:
    return walls_grid(ELL, 0.05, bounds=(-31.0, -1.0, 44.0, 31.0))


def ell_drive(scale: float = 1.0) -> tuple[list[ScanSample], list[float]]:
    """Scans every 0.5 m down B from y = 15 to A, then west along A to x = 20 (ranges cast in the
    true world), with odometry counting ``scale`` times the true distance (a wheel-radius error)."""
    from initcli.core.geometry.raycast import ray_segment_distances

    truth = [Pose2D(41.0, float(y), -math.pi / 2) for y in np.arange(15.0, 1.0, -0.5)]
    truth += [Pose2D(float(x), 1.0, math.pi) for x in np.arange(41.0, 19.9, -0.5)]
    angles = np.linspace(-math.pi, math.pi, 120, endpoint=False)
    scans, travel = [], []
    odom, distance = truth[0], 0.0
    for i, pose in enumerate(truth):
        if i:
            step = truth[i - 1].inverse() * pose
            odom = odom * Pose2D(scale * step.x, scale * step.y, step.yaw)
            distance += scale * math.hypot(step.x, step.y)
        ranges = ray_segment_distances(np.array([pose.x, pose.y]), angles - (-pose.yaw), ELL, 12.0)
        ranges = np.where(ranges < 12.0, ranges, np.inf)
        scans.append(ScanSample(odom, angles, ranges, 12.0))
        travel.append(distance)
    return scans, travel


def _track(transform: Pose2D, scans: list[ScanSample], travel: list[float]) -> np.ndarray:
    track = tracked_scan_fit(
        transform, scans, travel, LikelihoodField(ell_grid()), 0.25, 5.0, 0.3, math.radians(6.0)
    )
    assert track is not None
    return track.fits


def test_the_path_scans_fit_the_right_place_at_every_window_and_a_bay_off_only_recently() -> None:
    scans, travel = ell_drive()
    right = _track(Pose2D.identity(), scans, travel)
    bay_off = _track(Pose2D(-4.0, 0.0, 0.0), scans, travel)  # the robot placed 4 m farther west
    assert len(right) == len(bay_off) == 8  # 35 m of travel in windows of 5 m, newest first
    assert right.min() > 0.9
    assert bay_off[0] > 0.9  # from A's middle the two look alike ...
    assert bay_off[-1] < 0.5  # ... but not in B, where the path began
    params = VerificationParams()
    assert track_outranks(right, bay_off, params)
    assert not track_outranks(bay_off, right, params)


def test_the_path_scans_follow_odometry_drift_back_along_the_path() -> None:
    """With a 3 % wheel-scale error the odometry puts B 1 m off after 35 m: a single alignment of
    the whole path cannot fit both of its ends, the window-by-window track does."""
    scans, travel = ell_drive(scale=1.03)
    transform = Pose2D(20.0, 1.0, math.pi) * scans[-1].odom.inverse()  # right where the robot is now
    track = _track(transform, scans, travel)
    assert track.min() > 0.9
    whole = path_scan_fit(transform, scans, LikelihoodField(ell_grid()), 0.25, search_xy=0.3)
    assert whole is not None and whole < track.min() - 0.1


@pytest.mark.parametrize(
    ("track", "other", "expected"),
    [
        ([0.9, 0.9, 0.9], [0.9, 0.9, 0.5], True),  # some window 0.4 better, none worse
        ([0.9, 0.9, 0.9], [0.9, 0.95, 0.5], True),  # one window 0.05 worse: within the slack
        ([0.9, 0.9, 0.9], [0.9, 0.97, 0.5], False),  # 0.07 worse somewhere: the other holds its own
        ([0.9, 0.9, 0.9], [0.85, 0.8, 0.8], False),  # never 0.2 better: no lead
        ([0.6, 0.9, 0.9], [0.3, 0.5, 0.5], False),  # its own worst window below min_track_fit
        ([0.9, 0.9, 0.9, 0.9], [0.9, 0.9, 0.9], False),  # compared over the common windows only
        ([0.9, 0.9], [0.5, 0.5], False),  # two windows: the first 10 m are no path yet
        ([], [0.5], False),
    ],
)
def test_one_place_outranks_another_by_the_path_scans_only_plainly(
    track: list[float], other: list[float], expected: bool
) -> None:
    assert track_outranks(np.array(track), np.array(other), VerificationParams()) is expected


def test_a_place_needing_more_outliers_is_outranked_by_a_smaller_lead() -> None:
    """The doors (one outlier fewer) and the lidar (0.12 better in a window, never worse) agree."""
    mine, theirs = np.array([0.9, 0.85, 0.9, 0.8]), np.array([0.9, 0.85, 0.78, 0.8])
    params = VerificationParams()
    assert not track_outranks(mine, theirs, params)
    assert track_outranks(mine, theirs, params, trailing=True)
    # ... but not when the other holds its own somewhere, nor on a lead below the trailing lead
    assert not track_outranks(mine, np.array([0.9, 0.95, 0.78, 0.8]), params, trailing=True)
    assert not track_outranks(mine, np.array([0.9, 0.85, 0.85, 0.8]), params, trailing=True)


GOOD, BAY_OFF, TURNED = np.array([0.9, 0.9, 0.9]), np.array([0.9, 0.9, 0.4]), np.array([0.9, 0.85, 0.9])


def test_of_several_hypotheses_the_one_the_path_scans_plainly_favour_is_found() -> None:
    asked: list[int] = []

    def wide(k: int) -> np.ndarray:
        asked.append(k)
        return [GOOD, BAY_OFF, BAY_OFF][k]

    params = VerificationParams()
    tracks = [GOOD, BAY_OFF, BAY_OFF]
    assert track_favoured([True, True, True], [1, 1, 2], [6, 6, 5], tracks, wide, params) == 0
    assert sorted(asked) == [1, 2]  # the others searched wide before they count as outranked
    # one that fails the recent checks must be outranked as well (searched wide: here it still trails)
    assert track_favoured([True, True, False], [1, 1, 0], [6, 6, 5], tracks, wide, params) is None
    assert track_favoured([True, True, False], [1, 1, 1], [6, 6, 5], tracks, wide, params) == 0
    # one place alone passes the checks and outranks the other, which fails them: that one
    assert track_favoured([True, False], [1, 1], [6, 6], [GOOD, BAY_OFF], wide, params) == 0
    # a place one outlier worse is outranked by the trailing lead (0.12 here, not 0.2)
    near = np.array([0.9, 0.9, 0.78])
    assert track_favoured([True, True], [1, 1], [6, 6], [GOOD, near], lambda k: near, params) is None
    assert track_favoured([True, True], [1, 2], [6, 5], [GOOD, near], lambda k: near, params) == 0


@pytest.mark.parametrize(
    ("passed", "outliers", "inliers", "tracks", "widened"),
    [
        ([True, True], [1, 1], [6, 6], [GOOD, TURNED], None),  # the other fits every window as well
        ([True, True], [2, 1], [6, 6], [GOOD, BAY_OFF], None),  # the best fit explains fewer detections
        ([True, True], [1, 1], [3, 6], [GOOD, BAY_OFF], None),  # too few matched features to claim
        ([True], [1], [6], [GOOD], None),  # one hypothesis: nothing to tell apart here
        ([True, True], [1, 1], [6, 6], [GOOD, BAY_OFF], GOOD),  # searched wide the other fits as well
        # the true place found 1.5 m off fails the recent checks; searched wide it fits as well
        ([True, True, False], [0, 1, 0], [6, 6, 6], [GOOD, BAY_OFF, BAY_OFF], GOOD),
    ],
)
def test_no_hypothesis_is_favoured_unless_it_plainly_stands_out(
    passed: list[bool],
    outliers: list[int],
    inliers: list[int],
    tracks: list[np.ndarray],
    widened: np.ndarray | None,
) -> None:
    found = track_favoured(
        passed,
        outliers,
        inliers,
        tracks,
        lambda k: tracks[k] if widened is None else widened,
        VerificationParams(),
    )
    assert found is None
