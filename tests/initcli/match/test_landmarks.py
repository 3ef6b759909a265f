"""initcli.match.landmarks: a log's lidar landmarks (its records, or found in its scans by the tracker
the session runs) and Algorithm 1 on them, with the camera seeing nothing."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from shapely.geometry import Polygon

from bimtools.extract.landmarks import storey_landmarks
from bimtools.site.load import Site, StoreyModel
from bimtools.site.manifest import SiteManifest
from bimtools.site.records import LIDAR, Feature
from initcli.config.session import VerificationSection
from initcli.core.features.classes import ClassMap
from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.ranking import Verdict
from initcli.core.lidar.landmark_tracks import LandmarkTracker, ScanInput
from initcli.core.lidar.scan_landmarks import ScanLandmarkParams
from initcli.core.verify.checks import CameraView, VerificationParams
from initcli.drivers.base import LaserScan, SensorFrame
from initcli.io.detection_log import DetectionLog, FeatureRecord, Meta, Odom, Record, Scan, read_log
from initcli.match.landmarks import feature_records, log_landmarks, site_tracker, travel_at
from initcli.match.pipeline import MatchOptions, match_log
from initcli.session.claims import ClaimChecks
from initcli.session.perception import Perception
from initcli.session.result import SessionResult
from initcli.verify.evidence import PathEvidence, StoreyEvidence, verify_transform, without_landmark_misses
from tests.landmark_worlds import RANGE_MAX, SETTINGS, walled

# A staircase-shaped floor: corners in no symmetric pattern.
WORLD = walled(Polygon([(0, 0), (10, 0), (10, 3), (7, 3), (7, 6), (3, 6), (3, 9), (0, 9)]))
START = Pose2D(1.0, 1.0, 0.0)  # the odom frame's origin in the BIM frame
ROUTE = [(1.0, 1.0), (9.0, 1.5), (5.0, 2.0), (5.0, 5.0), (1.5, 5.0), (1.5, 8.0)]


def _site(tmp_path: Path, landmarks: bool = True) -> Site:
    rows = storey_landmarks(WORLD.plan.walls, SETTINGS, "L", 0.0, WORLD.free) if landmarks else []
    manifest = SiteManifest(
        "w.ifc", "", "IFC4", "", "m", 1.0, 1.0, 0.05, landmarks=SETTINGS if landmarks else None
    )
    return Site(tmp_path, {"L": StoreyModel("L", 0.0, rows)}, manifest)


def _scans(seed: int = 0, step: float = 0.25) -> tuple[list[ScanInput], Pose2D]:
    rng = np.random.default_rng(seed)
    out, t, pose = [], 0.0, START
    for (x0, y0), (x1, y1) in zip(ROUTE, ROUTE[1:], strict=False):
        yaw = math.atan2(y1 - y0, x1 - x0)
        n = max(1, int(math.hypot(x1 - x0, y1 - y0) / step))
        for k in range(n):
            pose = Pose2D(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, yaw)
            r, a0, inc = WORLD.scan(pose.x, pose.y, pose.yaw, rng)
            out.append(ScanInput(t, START.inverse().compose(pose), np.round(r, 3), a0, inc, RANGE_MAX))
            t += 0.5
    return out, pose


def _log(scans: list[ScanInput], extra: list[Record] = ()) -> DetectionLog:
    records: list[Record] = []
    for s in scans:
        records.append(Odom(s.t, s.pose.x, s.pose.y, s.pose.yaw))
        records.append(Scan(s.t, s.angle_min, s.angle_increment, s.range_max, tuple(s.ranges.tolist())))
    records += list(extra)
    records.sort(key=lambda r: r.t)  # type: ignore[union-attr]
    return DetectionLog(
        Path("w.jsonl"), Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), records, list(range(len(records)))
    )


def test_scans_replay_to_the_landmarks_the_session_logs(tmp_path) -> None:
    site = _site(tmp_path)
    scans, _ = _scans()
    tracker = LandmarkTracker(ScanLandmarkParams.from_rules(SETTINGS))
    online = feature_records([f for s in scans for f in tracker.add_scan(s)])  # the session's way
    notes: list[str] = []
    offline = log_landmarks(_log(scans), site, notes)
    assert online and offline == online
    assert all(r.source == LIDAR for r in offline) and "found in the log's" in notes[0]
    # a log that holds the records is read as it is (its scans are not searched again)
    moved = [type(r)(r.t, r.cls, r.x + 1.0, r.y, r.source) for r in online]
    assert log_landmarks(_log(scans, moved), site, []) == moved


def test_the_camera_off_the_lidar_landmarks_place_the_robot(tmp_path) -> None:
    site = _site(tmp_path)
    scans, end = _scans()
    report = match_log(_log(scans), site, MatchOptions(), ClassMap())
    assert report.verdict == "unique match", (report.verdict, report.notes)
    best = report.hypotheses[0]
    assert best.pose.distance_to(end) < 0.1 and best.pose.yaw_error(end) < math.radians(2)
    assert best.n_inliers >= MatchOptions().min_inliers / MatchOptions().landmark_weight
    off = match_log(_log(scans), site, MatchOptions(landmarks=False), ClassMap())
    assert off.hypotheses == [] and off.verdict == "no consistent match"


def test_a_site_without_landmarks_leaves_the_logs_out_with_a_note(tmp_path) -> None:
    scans, _ = _scans()
    tracker = LandmarkTracker(ScanLandmarkParams.from_rules(SETTINGS))
    records = feature_records([f for s in scans for f in tracker.add_scan(s)])
    notes: list[str] = []
    assert log_landmarks(_log(scans, records), _site(tmp_path, landmarks=False), notes) == []
    assert "the site has no landmarks" in notes[0]


def test_travel_at_sums_the_odometry_path() -> None:
    odom = [Odom(0.0, 0.0, 0.0, 0.0), Odom(1.0, 3.0, 4.0, 0.0), Odom(2.0, 3.0, 5.0, 0.0)]
    assert travel_at(odom, [-1.0, 0.5, 1.0, 9.0]).tolist() == [0.0, 0.0, 5.0, 6.0]


def test_the_sessions_log_replays_to_its_landmarks_and_verdict(tmp_path) -> None:
    site = _site(tmp_path)
    scans, _ = _scans()
    options = MatchOptions()
    path = tmp_path / "session.jsonl"
    perception = Perception(
        Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), path, ClassMap(), options, 0.0, 1, site_tracker(site)
    )
    for step, s in enumerate(scans):
        scan = LaserScan(s.angle_min, s.angle_increment, s.range_max, s.ranges)
        perception.record_frame(SensorFrame(s.t, s.pose, scan, []), step)
    assert perception.new_features() and perception.n_features == len(perception.lidar) > 0
    online = perception.match(scans[-1].t, site)
    perception.close()
    log = read_log(path)
    assert [f for f in log.features if f.source == LIDAR] == perception.lidar
    offline = match_log(log, site, options, ClassMap())
    assert online.verdict == offline.verdict == "unique match"
    assert offline.hypotheses[0].matches == online.hypotheses[0].matches


def test_landmarks_the_bim_lacks_never_cost_the_camera_its_match(tmp_path) -> None:
    site = _site(tmp_path)
    doors = [(0.5, 0.0), (4.0, 0.0), (9.0, 0.0), (10.0, 2.0), (5.0, 6.0)]
    site.storeys["L"].features += [
        Feature(f"d{i}", "Door", x, y, 0.0, 1.0, 0.9, 2.1, "L") for i, (x, y) in enumerate(doors)
    ]
    to_odom = START.inverse()
    records: list[Record] = [Odom(0.0, 0.0, 0.0, 0.0)]
    for i, (x, y) in enumerate(doors):
        p = to_odom.apply(np.array([[x, y]]))[0]
        records.append(FeatureRecord(1.0 + i, "Door", float(p[0]), float(p[1])))
    rng = np.random.default_rng(5)
    for k, (x, y) in enumerate(rng.uniform(20, 60, size=(8, 2))):  # geometry the BIM lacks
        records.append(FeatureRecord(10.0 + k, "ConcaveCorner", float(x), float(y), LIDAR))
    log = DetectionLog(
        Path("w.jsonl"), Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), records, list(range(len(records)))
    )
    report = match_log(log, site, MatchOptions(), ClassMap())
    assert report.verdict == "unique match", report.notes
    assert report.hypotheses[0].pose.distance_to(START) < 0.05
    # every corner is declared geometry the BIM lacks, every door is matched
    pairs = list(zip((f.cls for f in report.features), report.hypotheses[0].matches, strict=True))
    assert [m for c, m in pairs if c == "door"] == [f"d{i}" for i in range(5)]
    assert [m for c, m in pairs if c != "door"] == [None] * 8


def test_a_claim_is_held_back_by_the_corners_the_lidar_should_have_confirmed(tmp_path) -> None:
    site = _site(tmp_path)
    scans, _ = _scans()
    log = _log(scans)
    confirmed = log_landmarks(log, site, [])
    path = PathEvidence.of_log(log)
    storey = StoreyEvidence.of(site.storeys["L"], ClassMap())
    view = CameraView(DEFAULT_CAMERA, DEFAULT_MOUNT, 0.1)
    params = VerificationParams()
    right = verify_transform(START, storey, path, [], view, params, confirmed)
    assert right.passed and right.landmarks_predicted >= 5
    assert right.landmarks_missed <= right.landmarks_predicted // 3
    assert right.as_dict()["landmarks_predicted"] == right.landmarks_predicted
    # nothing confirmed: every corner in view is a miss, and the claim is held back ...
    blind_lidar = verify_transform(START, storey, path, [], view, params, [])
    assert blind_lidar.landmarks_missed == blind_lidar.landmarks_predicted == right.landmarks_predicted
    assert not blind_lidar.passed and "lidar landmarks in view were never seen" in blind_lidar.reasons[-1]
    # ... though never a rival ruled out by them, nor a fine pose failed
    assert verify_transform(START, storey, path, [], view, without_landmark_misses(params), []).passed
    # a place turned half round predicts corners where none was confirmed
    turned = START.compose(Pose2D(4.0, 2.0, math.pi))
    wrong = verify_transform(turned, storey, path, [], view, params, confirmed)
    assert wrong.landmarks_missed > right.landmarks_missed


def test_no_landmark_evidence_where_the_lidars_landmarks_are_not_tracked(tmp_path) -> None:
    site = _site(tmp_path)
    scans, _ = _scans()
    log = _log(scans)
    path = PathEvidence.of_log(log)
    storey = StoreyEvidence.of(site.storeys["L"], ClassMap())
    view = CameraView(DEFAULT_CAMERA, DEFAULT_MOUNT, 0.1)
    untracked = verify_transform(START, storey, path, [], view, VerificationParams(), None)
    assert untracked.passed and untracked.landmarks_predicted == untracked.landmarks_missed == 0
    # bim-init match: the landmarks the report was matched with are those the checks compare ...
    on = match_log(log, site, MatchOptions(), ClassMap())
    assert on.landmarks == log_landmarks(log, site, []) and on.landmarks
    # ... and with matching.landmarks off none is tracked, so none counts as missed
    assert match_log(log, site, MatchOptions(landmarks=False), ClassMap()).landmarks is None
    # the session: a perception with no landmark tracker gives its claims no landmark evidence
    predicted = []
    for tracker in (None, site_tracker(site)):
        perception = Perception(
            Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), None, ClassMap(), MatchOptions(), 0.0, 1, tracker
        )
        for step, s in enumerate(scans):
            scan = LaserScan(s.angle_min, s.angle_increment, s.range_max, s.ranges)
            perception.record_frame(SensorFrame(s.t, s.pose, scan, []), step)
        result = SessionResult(False, "", None)
        claims = ClaimChecks(VerificationSection(), site, perception, view, result, lambda t, why: None)
        predicted.append(claims.verify("L", START).landmarks_predicted)
    assert predicted[0] == 0 < predicted[1]


def test_corners_the_bim_lacks_never_single_out_a_wrong_place(tmp_path) -> None:
    """A corridor alike turned half round (doors point-symmetric about its centre): the doors alone
    fit two places. Two clutter corners, which the BIM lacks, fit by chance two corners of the turned
    place. Within an outlier budget of a third of the landmarks (one of two) only the turned place
    would survive; with the camera's features in the sequence every landmark may be an outlier, and
    the verdict is the doors' own."""
    centre = np.array([5.0, 3.0])
    doors = [(0.0, 0.0), (7.0, 0.0), (10.0, 0.0)]
    clutter = [(2.0, 1.5), (9.0, 2.0)]
    rows = [Feature(f"d{i}", "Door", x, y, 0.0, 1.0, 0.9, 2.1, "L") for i, (x, y) in enumerate(doors)]
    rows += [
        Feature(f"t{i}", "Door", *(2 * centre - p), 0.0, -1.0, 0.9, 2.1, "L") for i, p in enumerate(doors)
    ]
    rows += [
        Feature(f"c{i}-CC1", "ConcaveCorner", *(2 * centre - p), 0.0, 1.0, 0.5, 0.0, "L", ifc_class="IfcWall")
        for i, p in enumerate(clutter)
    ]
    manifest = SiteManifest("w.ifc", "", "IFC4", "", "m", 1.0, 1.0, 0.05, landmarks=SETTINGS)
    site = Site(tmp_path, {"L": StoreyModel("L", 0.0, rows)}, manifest)
    seen = [("Door", doors[0]), ("ConcaveCorner", clutter[0]), ("Door", doors[1])]
    seen += [("Door", doors[2]), ("ConcaveCorner", clutter[1])]
    records: list[Record] = [Odom(0.0, 0.0, 0.0, 0.0)]  # the odom frame is the BIM frame
    for k, (cls, (x, y)) in enumerate(seen):
        records.append(FeatureRecord(1.0 + k, cls, x, y, LIDAR if cls == "ConcaveCorner" else "camera"))
    log = DetectionLog(
        Path("w.jsonl"), Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), records, list(range(len(records)))
    )
    report = match_log(log, site, MatchOptions(), ClassMap())
    camera_alone = match_log(log, site, MatchOptions(landmarks=False), ClassMap())
    assert report.outcome is Verdict.AMBIGUOUS and report.n_hypotheses == camera_alone.n_hypotheses
    # the two places without a camera outlier: the turned one with the clutter seen after its second
    # door fitted, the true one
    best = {tuple(h.matches) for h in report.hypotheses if h.n_outliers == 0}
    assert best == {("d0", None, "d1", "d2", None), ("t0", None, "t1", "t2", "c1-CC1")}
    truth = next(h for h in report.hypotheses if h.matches[0] == "d0")
    assert truth.transform.distance_to(Pose2D(0.0, 0.0, 0.0)) < 0.05


def test_a_false_door_and_a_clutter_corner_leave_the_true_place_listed(tmp_path) -> None:
    """Rule 1 (sub-matches of a match with fewer camera outliers are dropped) over the camera's
    columns: the true place, one door a false detection and one corner clutter, is a hypothesis (it
    once dominated itself, its landmark outlier counted as a camera one, so every alternative with
    a camera outlier vanished where a landmark was skipped, the rival search's among them)."""
    doors = [(0.0, 0.0), (7.0, 0.0), (10.0, 0.0), (3.0, 6.0)]
    rows = [Feature(f"d{i}", "Door", x, y, 0.0, 1.0, 0.9, 2.1, "L") for i, (x, y) in enumerate(doors)]
    rows.append(Feature("c0-CC1", "ConcaveCorner", 5.0, 6.0, 0.0, -1.0, 0.5, 0.0, "L", ifc_class="IfcWall"))
    manifest = SiteManifest("w.ifc", "", "IFC4", "", "m", 1.0, 1.0, 0.05, landmarks=SETTINGS)
    site = Site(tmp_path, {"L": StoreyModel("L", 0.0, rows)}, manifest)
    seen = [("Door", (0.0, 0.0)), ("Door", (7.0, 0.0)), ("ConcaveCorner", (2.0, 1.5))]
    seen += [("Door", (30.0, -20.0)), ("Door", (10.0, 0.0)), ("Door", (3.0, 6.0))]
    records: list[Record] = [Odom(0.0, 0.0, 0.0, 0.0)]
    for k, (cls, (x, y)) in enumerate(seen):
        records.append(FeatureRecord(1.0 + k, cls, x, y, LIDAR if cls == "ConcaveCorner" else "camera"))
    log = DetectionLog(
        Path("w.jsonl"), Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), records, list(range(len(records)))
    )
    report = match_log(log, site, MatchOptions(), ClassMap())
    truth = [h for h in report.hypotheses if h.matches == ["d0", "d1", None, None, "d2", "d3"]]
    assert truth and truth[0].n_outliers == 1 and truth[0].pose.distance_to(Pose2D(0.0, 0.0, 0.0)) < 0.05
    assert report.verdict == "unique match", [h.matches for h in report.hypotheses]


def test_landmarks_alone_claim_one_place_only_if_every_landmark_may_be_clutter(tmp_path) -> None:
    """The camera off: a storey alike turned half round, two clutter corners seen first that fit two
    corners of the turned place only. Within the budget (one landmark of the first two) the true
    place dies and the turned one is unique; with every landmark allowed to be clutter both stand."""
    rng = np.random.default_rng(11)
    true_corners, clutter = rng.uniform(2, 18, size=(6, 2)), rng.uniform(2, 18, size=(2, 2))
    centre = np.array([10.0, 10.0])
    rows = [
        Feature(
            f"{name}{i}-CC1",
            "ConcaveCorner",
            float(x),
            float(y),
            1.0,
            0.0,
            0.5,
            0.0,
            "L",
            ifc_class="IfcWall",
        )
        for name, pts in (("t", true_corners), ("r", 2 * centre - true_corners), ("q", 2 * centre - clutter))
        for i, (x, y) in enumerate(pts)
    ]
    manifest = SiteManifest("w.ifc", "", "IFC4", "", "m", 1.0, 1.0, 0.05, landmarks=SETTINGS)
    site = Site(tmp_path, {"L": StoreyModel("L", 0.0, rows)}, manifest)
    records: list[Record] = [Odom(0.0, 0.0, 0.0, 0.0)]
    for k, (x, y) in enumerate(np.vstack([clutter, true_corners])):
        records.append(FeatureRecord(1.0 + k, "ConcaveCorner", float(x), float(y), LIDAR))
    log = DetectionLog(
        Path("w.jsonl"), Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), records, list(range(len(records)))
    )
    report = match_log(log, site, MatchOptions(), ClassMap())
    assert report.outcome is Verdict.AMBIGUOUS, [h.matches for h in report.hypotheses]
    assert any("unique match within the lidar landmarks' outlier budget" in n for n in report.notes)
    places = {tuple(h.matches) for h in report.hypotheses}
    assert (None, None, *(f"t{i}-CC1" for i in range(6))) in places
    assert (*(f"q{i}-CC1" for i in range(2)), *(f"r{i}-CC1" for i in range(6))) in places
