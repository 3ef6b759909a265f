"""initcli.session.claims: a claim's checks, its rivals and the final pose, on two corridors with the
same doors on their north walls; corridor B also has lifts all along its south wall. The robot drove
along A and saw its doors: Algorithm 1 cannot tell the corridors apart, the negative evidence can
(B's lifts were in view and never seen)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from bimtools.site.load import Site, load_site
from initcli.config.session import VerificationSection
from initcli.core.features.classes import ClassMap
from initcli.core.geometry.projection import CameraIntrinsics
from initcli.core.geometry.se2 import Pose2D
from initcli.core.verify.checks import CameraView
from initcli.drivers.base import SensorFrame
from initcli.io.detection_log import read_log
from initcli.io.log_writer import write_log
from initcli.match.pipeline import Hypothesis, MatchOptions, MatchReport, match_log
from initcli.match.sightings import sightings_from_log
from initcli.session.claims import ClaimChecks
from initcli.session.perception import Perception
from initcli.session.result import SessionResult
from initcli.sim.synthetic_floor import write_site_folder
from initcli.sim.synthetic_log import SimFeature, SyntheticParams, make_log, path_from_waypoints
from initcli.verify.evidence import PathEvidence
from tests.helpers import rooms_map

DOORS_X = (3.0, 6.0, 13.0, 19.5)  # no mirror image of itself: the reversed corridor matches nothing
CAMERA = CameraIntrinsics(320.0, 320.0, 320.0, 240.0, 640, 480)


SOUTH_X = tuple(float(x) for x in range(2, 30, 2))


def corridor(y: float, prefix: str, xs: tuple[float, ...]) -> list[SimFeature]:
    return [SimFeature(f"{prefix}{i}", "door", x, y + 1.0, 0.0, -1.0, 1.0, 2.1) for i, x in enumerate(xs)]


def lifts(y: float, prefix: str, xs: tuple[float, ...]) -> list[SimFeature]:
    """Lifts on the south wall (y - 1) of a corridor along x, facing into it (+y)."""
    return [SimFeature(f"{prefix}L{i}", "lift", x, y - 1.0, 0.0, 1.0, 1.0, 2.1) for i, x in enumerate(xs)]


def walls(y: float) -> np.ndarray:
    return np.array([[0.0, y - 1.0, 32.0, y - 1.0, 0.0, 1.0], [0.0, y + 1.0, 32.0, y + 1.0, 0.0, -1.0]])


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory) -> tuple[Site, Perception, MatchReport]:
    """The site, what the robot perceived along corridor A, and the match on it."""
    tmp = tmp_path_factory.mktemp("claims")
    a = corridor(0.0, "A", DOORS_X)
    b = corridor(12.0, "B", DOORS_X) + lifts(12.0, "B", SOUTH_X)
    site_dir = write_site_folder(tmp / "site", {"L1": (a + b, np.vstack([walls(0.0), walls(12.0)]))})
    t, path = path_from_waypoints([(1.0, 0.0), (30.0, 0.0)], start_yaw=0.0)
    log = make_log(a, t, path, camera=CAMERA, params=SyntheticParams(empty_detections=True), seed=3)
    write_log(tmp / "a.jsonl", log.records)
    read = read_log(tmp / "a.jsonl")
    options = MatchOptions(max_outliers=0)
    cmap = ClassMap({})
    perception = Perception(read.meta, None, cmap, options, drift_window=0.0, scan_every=5)
    perception.log = read
    perception.sightings = sightings_from_log(read, cmap, options.edge_margin)
    perception.path = PathEvidence.of_log(read)
    perception.travel = perception.path.image_travel[-1]
    loaded = load_site(Path(site_dir))
    site = Site(
        loaded.root,
        {
            "L1": dataclasses.replace(
                loaded.storeys["L1"],
                grid=rooms_map([(0.0, -1.0, 32.0, 1.0), (0.0, 11.0, 32.0, 13.0)], 36.0, 17.0),
            )
        },
    )
    report = match_log(read, site, options, cmap, perception.sightings)
    return site, perception, report


def checks_of(
    drive: tuple[Site, Perception, MatchReport], **changed: object
) -> tuple[ClaimChecks, SessionResult, list[str]]:
    site, perception, _ = drive
    result, notes = SessionResult(False, "", None), []
    view = CameraView(CAMERA, perception.meta.camera_pose, perception.options.min_depth)
    checks = dataclasses.replace(VerificationSection(), **changed)  # type: ignore[arg-type]
    return (
        ClaimChecks(checks, site, perception, view, result, lambda t, why: notes.append(why)),
        result,
        notes,
    )


def facing_east(report: MatchReport, y: float) -> Hypothesis:
    """The hypothesis in the corridor at ``y`` that faces the way the robot drove."""
    return next(h for h in report.hypotheses if abs(h.pose.yaw) < 0.5 and abs(h.pose.y - y) < 2.0)


def claim_of(report: MatchReport, h: Hypothesis) -> MatchReport:
    """``report`` as a unique match on ``h`` alone."""
    return dataclasses.replace(report, hypotheses=[h], n_hypotheses=1)


def last_frame(perception: Perception) -> SensorFrame:
    return SensorFrame(30.0, perception.path.image_poses[-1])


def test_the_checks_pass_the_corridor_driven_and_fail_the_one_with_doors_never_seen(drive) -> None:
    claims, result, _ = checks_of(drive)
    _, perception, report = drive
    frame = last_frame(perception)
    a, b = facing_east(report, 0.0), facing_east(report, 12.0)
    here = claims.verify(a.storey, a.reported_pose * frame.odom.inverse())
    there = claims.verify(b.storey, b.reported_pose * frame.odom.inverse())
    assert here.passed and here.missed_predictions == 0
    assert not there.passed and there.missed_predictions >= 10 and "BL5" in there.missed_ids
    assert result.verifications == []  # checking is not recording
    claims.record(frame, "coarse", b.storey, b.reported_pose, there)
    assert result.verifications[0]["stage"] == "coarse" and result.verifications[0]["passed"] is False


def test_a_claim_waits_for_enough_matched_features(drive) -> None:
    _, perception, report = drive
    claims, result, notes = checks_of(drive, min_claim_inliers=5)
    a = facing_east(report, 0.0)
    assert claims.verified(last_frame(perception), claim_of(report, a)) == (False, None, [])
    assert notes == ["unique match on 4 features: waiting for 5"] and result.verifications == []
    off, result, _ = checks_of(drive, enabled=False)
    assert off.verified(last_frame(perception), claim_of(report, a)) == (True, None, [])


def test_a_rival_that_fails_the_checks_is_no_reason_to_doubt_the_claim(drive) -> None:
    """Claim A: with one more outlier allowed corridor B is a rival, but B fails the checks (its
    lifts were in view and never seen): A is claimed."""
    _, perception, report = drive
    claims, result, notes = checks_of(drive)
    ok, aligned, held = claims.verified(last_frame(perception), claim_of(report, facing_east(report, 0.0)))
    assert ok and held == [] and claims.doubted_at is None, (notes, result.verifications)
    assert any("rival(s)" in n and "none passes the checks" in n for n in notes), notes
    assert result.verifications[-1]["stage"] == "coarse" and result.verifications[-1]["passed"]


def test_a_rival_that_passes_the_checks_holds_the_claim_back_and_widens_the_next_search(drive) -> None:
    """Claim B (wrong: its lifts were never seen): corridor A, a rival, passes the checks; the
    claim is held back with A as the rival to go and look at, and the claims in the next
    ``rivals.doubt_window`` m of travel get the wide rival search."""
    _, perception, report = drive
    claims, result, notes = checks_of(drive)
    ok, aligned, held = claims.verified(last_frame(perception), claim_of(report, facing_east(report, 12.0)))
    assert not ok and aligned is None
    assert any(abs(h.pose.y) < 2.0 for h in held)  # corridor A
    assert claims.doubted_at == perception.travel and claims.doubted()
    assert any("pass the checks too" in n for n in notes) and result.verifications == []
    travel = perception.travel
    try:
        perception.travel = travel + claims.checks.rivals.doubt_window + 0.1
        assert not claims.doubted()
    finally:
        perception.travel = travel


def test_more_rivals_than_are_checked_count_as_credible(drive) -> None:
    _, perception, report = drive
    claims, _, notes = checks_of(drive)
    claims.checks = dataclasses.replace(
        claims.checks, rivals=dataclasses.replace(claims.checks.rivals, checked=0, compared=0)
    )
    ok, _, held = claims.verified(last_frame(perception), claim_of(report, facing_east(report, 0.0)))
    assert not ok and held and any("pass the checks too" in n for n in notes)


def test_the_final_pose_must_pass_the_checks_and_agree_with_the_claim(drive) -> None:
    _, perception, report = drive
    claims, result, _ = checks_of(drive)
    frame = last_frame(perception)
    a = facing_east(report, 0.0)
    pose = a.reported_pose
    assert claims.final(frame, a.storey, pose, pose) is None
    assert result.verifications[-1]["stage"] == "fine" and result.verifications[-1]["agrees_with_coarse"]
    away = Pose2D(pose.x - 3.0, pose.y, pose.yaw)  # the coarse pose carried by odometry, 3 m back
    why = claims.final(frame, a.storey, pose, away)
    assert why == "the pose failed verification: fine tuning ended 3.0 m / 0 deg from the coarse pose"
    assert result.verifications[-1]["agrees_with_coarse"] is False
    lenient, _, _ = checks_of(drive, agree_distance=5.0)
    assert lenient.final(frame, a.storey, pose, away) is None
    b = facing_east(report, 12.0)
    why = claims.final(frame, b.storey, b.reported_pose, b.reported_pose)
    assert why is not None and "never detected" in why
    off, result, _ = checks_of(drive, enabled=False)
    assert off.final(frame, b.storey, b.reported_pose, away) is None and result.verifications == []


def test_no_lidar_along_the_path_picks_a_hypothesis_when_it_is_off(drive) -> None:
    _, perception, report = drive
    assert report.n_hypotheses >= 2
    for changed in ({"track_m": 0.0}, {"enabled": False}):
        claims, _, notes = checks_of(drive, **changed)
        assert claims.lidar_unique(last_frame(perception), report) is None and notes == []
