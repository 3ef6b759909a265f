"""Verification of hypotheses against a log (initcli.verify.evidence): negative evidence separates two
corridors that are alike but for one door, and neither is claimed while both fit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from bimtools.site.load import load_site
from initcli.core.features.detection_filter import DetectionFilter, Sighting
from initcli.core.geometry.projection import CameraIntrinsics
from initcli.core.hypotheses.ranking import Verdict
from initcli.core.verify.checks import VerificationParams
from initcli.io.detection_log import read_log
from initcli.io.log_writer import write_log
from initcli.match.pipeline import MatchOptions, run_match, site_class_map
from initcli.sim.synthetic_floor import write_site_folder
from initcli.sim.synthetic_log import SimFeature, SyntheticParams, make_log, path_from_waypoints
from initcli.verify.evidence import (
    SEEING_FEATURES,
    PathEvidence,
    StoreyEvidence,
    camera_blind,
    claim_params,
    verify_report,
)

DOORS_X = (3.0, 8.5, 13.0, 19.0)
CAMERA = CameraIntrinsics(320.0, 320.0, 320.0, 240.0, 640, 480)  # the session default: ~90 degrees
EXTRA_X = 25.0  # corridor B has one door more than corridor A


def corridor(y: float, prefix: str, xs: tuple[float, ...]) -> list[SimFeature]:
    """Doors on the north wall (y + 1) of a corridor along x, facing into it (-y)."""
    return [SimFeature(f"{prefix}{i}", "door", x, y + 1.0, 0.0, -1.0, 1.0, 2.1) for i, x in enumerate(xs)]


def walls(y: float) -> np.ndarray:
    return np.array([[0.0, y - 1.0, 32.0, y - 1.0, 0.0, 1.0], [0.0, y + 1.0, 32.0, y + 1.0, 0.0, -1.0]])


def test_negative_evidence_tells_two_corridors_alike_but_for_one_door(tmp_path: Path) -> None:
    a = corridor(0.0, "A", DOORS_X)
    b = corridor(12.0, "B", (*DOORS_X, EXTRA_X))
    site_dir = write_site_folder(tmp_path / "site", {"L1": (a + b, np.vstack([walls(0.0), walls(12.0)]))})
    # The robot drives along corridor A (where there is no door at x = 25), past x = 25.
    t, path = path_from_waypoints([(1.0, 0.0), (30.0, 0.0)], start_yaw=0.0)
    log = make_log(a, t, path, camera=CAMERA, params=SyntheticParams(empty_detections=True), seed=3)
    log_path = tmp_path / "a.jsonl"
    write_log(log_path, log.records)
    options = MatchOptions(max_outliers=0)
    report = run_match(log_path, site_dir, options)
    # Algorithm 1 cannot tell the corridors apart (nor the way along them): nothing is claimed.
    assert report.n_hypotheses >= 2 and report.outcome is not Verdict.UNIQUE
    site = load_site(Path(site_dir))
    checks = verify_report(read_log(log_path), site, report, site_class_map(site), VerificationParams())
    by_corridor = {}
    for h, check in zip(report.hypotheses, checks, strict=True):
        assert check is not None
        if abs(h.pose.yaw) < 0.5:  # the two hypotheses facing the way the robot drove
            by_corridor["A" if abs(h.pose.y) < 2.0 else "B"] = check
    assert set(by_corridor) == {"A", "B"}
    assert by_corridor["A"].missed_predictions == 0
    assert by_corridor["B"].missed_predictions >= 1
    assert "B4" in by_corridor["B"].missed_ids  # the door B has and A lacks was in view, never seen
    assert by_corridor["A"].predicted >= 3


def test_path_evidence_of_a_log_has_its_images_and_scans(tmp_path: Path) -> None:
    t, path = path_from_waypoints([(1.0, 0.0), (10.0, 0.0)], start_yaw=0.0)
    log = make_log(corridor(0.0, "A", DOORS_X), t, path, params=SyntheticParams(empty_detections=True))
    write_log(tmp_path / "a.jsonl", log.records)
    evidence = PathEvidence.of_log(read_log(tmp_path / "a.jsonl"))
    assert len(evidence.image_poses) == len(t)
    assert evidence.image_travel[-1] > 8.5
    assert evidence.image_travel == sorted(evidence.image_travel)


def test_the_path_keeps_a_scan_every_half_metre_for_its_last_hundred_metres() -> None:
    from initcli.core.geometry.se2 import Pose2D
    from initcli.verify.evidence import TRACK_KEPT_M, TRACK_STEP_M

    evidence = PathEvidence()
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    for k in range(1500):  # 150 m at 0.1 m between scans
        travel = 0.1 * k
        evidence.add_scan(Pose2D(travel, 0.0, 0.0), travel, angles, np.full(360, 3.0), 20.0)
    gaps = np.diff(evidence.track_travel)
    assert gaps.min() >= TRACK_STEP_M - 1e-9 and gaps.max() < TRACK_STEP_M + 0.1 + 1e-9
    assert evidence.track_travel[-1] - evidence.track_travel[0] <= TRACK_KEPT_M
    assert evidence.track_travel[0] >= 149.9 - TRACK_KEPT_M - TRACK_STEP_M
    scans, travel = evidence.along(20.0)
    assert len(scans) == len(travel) and 20.0 - TRACK_STEP_M <= travel[-1] - travel[0] <= 20.0
    assert len(scans[0].angles) == 60  # every third beam kept for the recent scans, every second of those
    assert evidence.along(1000.0)[0] == evidence.track
    assert PathEvidence().along(20.0) == ([], [])


def _corridor_storey() -> StoreyEvidence:
    """A closed corridor 1.6 m wide and 40 m long (x in [0, 40], y in [0, 1.6]); outside is unknown."""
    from initcli.core.filters.particle_filter import LikelihoodField
    from initcli.core.verify.checks import FreeSpace
    from tests.helpers import rooms_map

    grid = rooms_map([(0.0, 0.0, 40.0, 1.6)], 44.0, 5.6)
    empty = np.zeros((0, 2))
    return StoreyEvidence(
        [], empty, empty, np.zeros(0), [], np.zeros((0, 4)), LikelihoodField(grid), FreeSpace(grid, 0.3)
    )


def test_a_long_wall_drive_with_odometry_drift_stays_in_free_space_placed_window_by_window() -> None:
    """Odometry that turns 0.2 degrees per metre too much puts the right place's path of the last
    30 m through the corridor wall when one transform places all of it; placed window by window as
    the lidar along the path aligns it, the path lies in the corridor. A place across the wall gains
    nothing from that."""
    from initcli.core.geometry.projection import CameraMount
    from initcli.core.geometry.raycast import ray_segment_distances
    from initcli.core.geometry.se2 import Pose2D
    from initcli.core.verify.checks import CameraView
    from initcli.verify.evidence import verify_transform

    storey = _corridor_storey()
    segments = np.array(
        [[0.0, 0.0, 40.0, 0.0], [0.0, 1.6, 40.0, 1.6], [0.0, 0.0, 0.0, 1.6], [40.0, 0.0, 40.0, 1.6]]
    )
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    evidence = PathEvidence()
    odom, bias = Pose2D(1.0, 0.8, 0.0), np.radians(0.2)
    for k, x in enumerate(np.arange(1.0, 39.0, 0.25)):
        if k:
            odom = odom * Pose2D(0.25, 0.0, 0.25 * bias)  # the true step is straight on
        ranges = ray_segment_distances(np.array([x, 0.8]), angles, segments, 12.0)
        travel = x - 1.0
        evidence.add_scan(odom, travel, angles, np.where(ranges < 12.0, ranges, np.inf), 12.0)
        evidence.add_image(odom, travel)
    right = Pose2D(38.75, 0.8, 0.0) * odom.inverse()
    view = CameraView(CAMERA, CameraMount(0.2, 0.0, 1.0, 0.0, 0.0, 0.0), min_depth=0.5)
    params = VerificationParams()
    check = verify_transform(right, storey, evidence, [], view, params)
    assert check.passed, check.reasons
    assert check.path_free is not None and check.path_free >= params.min_path_free
    single = verify_transform(right, storey, evidence, [], view, VerificationParams(track_m=0.0))
    assert not single.passed and single.path_free is not None and single.path_free < params.min_path_free
    across = Pose2D(0.0, 1.7, 0.0) * right  # the same drive placed beside the corridor
    assert not verify_transform(across, storey, evidence, [], view, params).passed


def test_a_camera_that_fires_a_false_box_now_and_then_is_still_blind() -> None:
    """Negative evidence counts once the camera has confirmed features (Eq. 3), not once it fired a
    box: a false box, one sighting in one image, confirms nothing; a working camera confirms the
    doors it passes, and then the doors it missed count against a place."""
    params = VerificationParams()
    confirming = DetectionFilter(MatchOptions().filter_params())
    confirming.add(Sighting(t=21.6, cls="stairs", x=3.0, y=1.0, depth=4.8, frame=108))  # a phantom
    phantom = len(confirming.result().features)
    assert phantom == 0 and camera_blind(300, phantom)
    assert claim_params(params, camera_blind(300, phantom)).log_odds == math.inf
    for frame in range(3):  # two doors seen in three images
        confirming.add(Sighting(t=30.0 + frame, cls="door", x=8.0, y=0.0, depth=3.0, frame=150 + frame))
        confirming.add(Sighting(t=30.0 + frame, cls="door", x=8.0, y=4.0, depth=3.0, frame=150 + frame))
    seen = len(confirming.result().features)
    assert seen == SEEING_FEATURES and not camera_blind(300, seen)
    assert claim_params(params, camera_blind(300, seen)) == params
    assert camera_blind(300, SEEING_FEATURES - 1)  # one feature may be a poster seen as a door
    assert not camera_blind(0, 0)  # no images: nothing to judge the camera by


def test_a_place_registered_on_its_wall_beams_is_judged_on_them() -> None:
    """A room the map draws with its walls only, 0.4 m boxes along them that the scans see: every
    beam fits the walls too poorly for the scan-fit check, the beams on straight lines (``lines``,
    as a registration on its wall beams placed the robot) fit them; the room turned a quarter
    round still fails on them."""
    from initcli.core.filters.particle_filter import LikelihoodField
    from initcli.core.geometry.projection import CameraMount
    from initcli.core.geometry.raycast import ray_segment_distances
    from initcli.core.geometry.se2 import Pose2D
    from initcli.core.verify.checks import CameraView, FreeSpace
    from initcli.verify.evidence import verify_transform
    from tests.helpers import rooms_map

    grid = rooms_map([(0.0, 0.0, 12.0, 6.0)], 16.0, 10.0)
    empty = np.zeros((0, 2))
    storey = StoreyEvidence(
        [], empty, empty, np.zeros(0), [], np.zeros((0, 4)), LikelihoodField(grid), FreeSpace(grid, 0.3)
    )
    walls = [[0.0, 0.0, 12.0, 0.0], [12.0, 0.0, 12.0, 6.0], [12.0, 6.0, 0.0, 6.0], [0.0, 6.0, 0.0, 0.0]]
    boxes = []
    for x in np.arange(0.6, 11.0, 0.9):  # furniture the map lacks, along both long walls
        for y in (0.3, 5.3):
            boxes += [[x, y, x + 0.4, y], [x + 0.4, y, x + 0.4, y + 0.4]]
            boxes += [[x + 0.4, y + 0.4, x, y + 0.4], [x, y + 0.4, x, y]]
    segments = np.array(walls + boxes)
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    evidence = PathEvidence()
    for x in np.arange(2.0, 10.0, 0.25):
        ranges = ray_segment_distances(np.array([x, 3.0]), angles, segments, 12.0)
        odom = Pose2D(x, 3.0, 0.0)  # odometry is the truth: the transform is the identity
        evidence.add_scan(odom, x - 2.0, angles, np.where(ranges < 12.0, ranges, np.inf), 12.0)
        evidence.add_image(odom, x - 2.0)
    view = CameraView(CAMERA, CameraMount(0.2, 0.0, 1.0, 0.0, 0.0, 0.0), min_depth=0.5)
    params = VerificationParams()
    right = Pose2D(0.0, 0.0, 0.0)
    every = verify_transform(right, storey, evidence, [], view, params)
    assert every.scan_fit is not None and every.scan_fit < params.min_scan_fit and not every.passed
    on_walls = verify_transform(right, storey, evidence, [], view, params, None, 1.0)
    assert on_walls.passed, on_walls.reasons
    centre = Pose2D(6.0, 3.0, 0.0)
    turned = centre * Pose2D(0.0, 0.0, math.pi / 2) * centre.inverse()  # the room turned a quarter
    across = verify_transform(turned, storey, evidence, [], view, params, None, 1.0)
    assert not across.passed and across.scan_fit is not None and across.scan_fit < params.min_scan_fit
