"""Verification of hypotheses against a log (initcli.match.verify): negative evidence separates two
corridors that are alike but for one door, and neither is claimed while both fit."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bimtools.site.load import load_site
from initcli.core.projection import CameraIntrinsics
from initcli.core.verification import VerificationParams
from initcli.io.detection_log import read_log, write_log
from initcli.match.pipeline import MatchOptions, run_match, site_class_map
from initcli.match.verify import PathEvidence, verify_report
from initcli.sim.synthetic_floor import write_site_folder
from initcli.sim.synthetic_log import SimFeature, SyntheticParams, make_log, path_from_waypoints

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
    assert report.n_hypotheses >= 2 and report.exit_code != 0
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
