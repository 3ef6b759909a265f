"""The match pipeline on synthetic logs: exact matches, pose accuracy, invariance, ambiguity, outliers."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bimtools.site.load import load_site
from initcli.core.features.classes import ClassMap
from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.ranking import Verdict
from initcli.io.detection_log import read_log
from initcli.io.log_writer import write_log
from initcli.match.pipeline import MatchOptions, MatchReport, match_log, site_class_map
from initcli.sim.synthetic_floor import write_site_folder
from initcli.sim.synthetic_log import SimFeature, SyntheticParams, make_log, path_from_waypoints

# A corridor 40 m long, y in [0, 2]; doors at irregular spacing on both walls, stairs and a lift at the ends.
# Written as a hand-made Table 1 with the paper's category names.
BOTTOM = [2.0, 7.5, 11.0, 17.3, 24.0, 29.5, 33.0, 38.0]


TOP = [4.0, 9.0, 14.5, 20.0, 27.0, 35.5]


def corridor(
    dy: float = 0.0, rotate_about: tuple[float, float] | None = None, first_id: int = 62900
) -> list[SimFeature]:
    feats = [SimFeature(str(first_id + i), "door", x, 0.0, 0.0, 1.0, 1.0, 2.1) for i, x in enumerate(BOTTOM)]
    feats += [
        SimFeature(str(first_id + 20 + i), "door", x, 2.0, 0.0, -1.0, 1.0, 2.1) for i, x in enumerate(TOP)
    ]
    feats += [SimFeature(str(first_id + 40), "lift", 40.0, 1.0, -1.0, 0.0, 1.1, 2.1)]
    feats += [SimFeature(str(first_id + 41), "stairs", 0.0, 1.0, 1.0, 0.0, 1.2, 2.1)]
    out = []
    for f in feats:
        x, y, nx, ny = f.x, f.y + dy, f.norm_x, f.norm_y
        if rotate_about is not None:  # 180 deg about the point
            cx, cy = rotate_about
            x, y, nx, ny = 2 * cx - x, 2 * cy - y, -nx, -ny
        out.append(SimFeature(f.id, f.cls, x, y, nx, ny, f.width, f.height))
    return out


def table1_csv(path: Path, feats: list[SimFeature]) -> Path:
    names = {"door": "Doors", "lift": "Lift", "stairs": "Stairs"}
    rows = ["ID,Category,X (m),Y (m),Norm_X,Norm_Y,Width (m),Height (m)".replace(" (m)", "")]
    rows += [
        f"{f.id},{names[f.cls]},{f.x},{f.y},{f.norm_x:g},{f.norm_y:g},{f.width},{f.height}" for f in feats
    ]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def run(
    tmp: Path,
    site_path: Path,
    render: list[SimFeature],
    waypoints,
    *,
    phantoms=(),
    params=None,
    seed=0,
    transform=None,
    **options,
) -> tuple[MatchReport, Pose2D]:
    t, path = path_from_waypoints(waypoints)
    log = make_log(render, t, path, phantoms=phantoms, params=params, seed=seed, transform_odom=transform)
    log_path = tmp / f"log_{seed}.jsonl"
    write_log(log_path, log.records)
    site = load_site(site_path, with_maps=False)
    report = match_log(read_log(log_path), site, MatchOptions(**options), site_class_map(site))
    return report, log.final_pose


def expected_ids(report: MatchReport, feats: list[SimFeature], to_bim: Pose2D) -> list[str]:
    """The BIM feature each confirmed feature truly is (noise-free: mapped exactly onto it)."""
    bim = np.array([[f.x, f.y] for f in feats])
    out = []
    for f in report.features:
        p = to_bim.apply(np.array([f.x, f.y]))
        i = int(np.argmin(np.hypot(*(bim - p).T)))
        assert np.hypot(*(bim[i] - p)) < 1e-6
        out.append(feats[i].id)
    return out


@pytest.fixture()
def distinct_csv(tmp_path: Path) -> Path:
    return table1_csv(tmp_path / "table1.csv", corridor())


@pytest.mark.parametrize("method", ["paper", "rigid"])
@pytest.mark.parametrize(
    "waypoints", [[(1.0, 1.0), (22.0, 1.0)], [(39.0, 0.8), (16.0, 1.2)], [(5.0, 1.0), (30.0, 1.4)]]
)
def test_noise_free_log_gives_the_exact_match_and_pose(tmp_path, distinct_csv, method, waypoints) -> None:
    # The paper's alpha: at the default 0.8 the second pass is still ambiguous at its end.
    report, truth = run(tmp_path, distinct_csv, corridor(), waypoints, pose_method=method, alpha=0.5)
    assert report.verdict == "unique match" and report.outcome is Verdict.UNIQUE
    (h,) = report.hypotheses
    to_bim = Pose2D(
        waypoints[0][0],
        waypoints[0][1],
        math.atan2(waypoints[1][1] - waypoints[0][1], waypoints[1][0] - waypoints[0][0]),
    )
    assert h.matches == expected_ids(report, corridor(), to_bim)
    assert h.n_outliers == 0 and h.cost < 1e-9
    assert h.pose.distance_to(truth) < 1e-3
    assert h.pose.yaw_error(truth) < 1e-3
    assert h.rectified_pose is None  # a bare features.csv has no walls


def test_invariant_under_rigid_transforms_of_the_odom_frame(tmp_path, distinct_csv) -> None:
    waypoints = [(3.0, 1.0), (26.0, 1.0)]
    base, truth = run(tmp_path, distinct_csv, corridor(), waypoints, pose_method="paper")
    rng = np.random.default_rng(2024)
    for k in range(8):
        t = Pose2D(*rng.uniform(-1000, 1000, 2), rng.uniform(-math.pi, math.pi))
        for method in ("paper", "rigid"):
            got, _ = run(
                tmp_path,
                distinct_csv,
                corridor(),
                waypoints,
                transform=lambda p, t=t: t * p,
                seed=k,
                pose_method=method,
            )
            assert got.verdict == base.verdict
            assert [h.matches for h in got.hypotheses] == [h.matches for h in base.hypotheses]
            assert [round(h.cost, 9) for h in got.hypotheses] == [round(h.cost, 9) for h in base.hypotheses]
            assert got.hypotheses[0].pose.distance_to(truth) < 1e-6
            assert got.hypotheses[0].pose.yaw_error(truth) < 1e-6


def test_periodic_doors_are_ambiguous(tmp_path) -> None:
    # doors every 4 m on both walls of an 80 m corridor: a view of 8 doors fits many places
    feats = [SimFeature(f"b{i}", "door", 2.0 + 4 * i, 0.0, 0.0, 1.0) for i in range(20)]
    feats += [SimFeature(f"t{i}", "door", 2.0 + 4 * i, 2.0, 0.0, -1.0) for i in range(20)]
    csv = table1_csv(tmp_path / "periodic.csv", feats)
    report, truth = run(tmp_path, csv, feats, [(24.0, 1.0), (40.0, 1.0)])
    assert report.outcome is Verdict.AMBIGUOUS and report.n_hypotheses > 2
    assert report.verdict == f"{report.n_hypotheses} hypotheses"
    assert any(h.pose.distance_to(truth) < 1e-3 for h in report.hypotheses) or report.n_hypotheses > 5


def test_point_symmetric_layout_is_never_unique(tmp_path) -> None:
    # the corridor and its copy rotated 180 deg: every view has a congruent twin
    feats = corridor() + corridor(rotate_about=(20.0, 11.0), first_id=70000)
    csv = table1_csv(tmp_path / "twins.csv", feats)
    rng = np.random.default_rng(5)
    for k in range(6):
        x0 = float(rng.uniform(1, 20))
        x1 = x0 + float(rng.uniform(8, 19))
        waypoints = [(x0, 1.0), (x1, 1.0)] if k % 2 == 0 else [(40 - x0, 1.0), (40 - x1, 1.0)]
        report, truth = run(tmp_path, csv, feats, waypoints, seed=k)
        assert report.outcome in (Verdict.AMBIGUOUS, Verdict.NONE), report.verdict
        if report.outcome is Verdict.AMBIGUOUS:
            assert report.n_hypotheses >= 2
            assert any(h.pose.distance_to(truth) < 1e-3 for h in report.hypotheses)


def test_a_persistent_false_positive_is_tolerated_with_one_outlier(tmp_path, distinct_csv) -> None:
    poster = SimFeature("poster", "door", 13.0, 0.0, 0.0, 1.0)  # looks like a door, not in the BIM
    waypoints = [(1.0, 1.0), (26.0, 1.0)]
    strict, truth = run(
        tmp_path, distinct_csv, corridor(), waypoints, phantoms=[poster], max_outliers=0, outlier_share=0.0
    )
    assert not any(
        h.pose.distance_to(truth) < 0.5 for h in strict.hypotheses
    )  # the paper's algorithm loses it
    assert strict.outcome is not Verdict.UNIQUE or strict.hypotheses[0].pose.distance_to(truth) > 0.5
    tolerant, truth = run(tmp_path, distinct_csv, corridor(), waypoints, phantoms=[poster], max_outliers=1)
    assert tolerant.verdict == "unique match"
    (h,) = tolerant.hypotheses
    assert h.n_outliers == 1 and h.matches.count(None) == 1
    outlier = tolerant.features[h.matches.index(None)]
    assert Pose2D(1.0, 1.0, 0.0).apply(np.array([outlier.x, outlier.y])) == pytest.approx(
        [13.0, 0.0], abs=1e-6
    )
    assert h.pose.distance_to(truth) < 1e-3


def test_a_misclassified_detection_is_tolerated(tmp_path, distinct_csv) -> None:
    render = [
        SimFeature(f.id, "lift", f.x, f.y, f.norm_x, f.norm_y) if f.id == "62903" else f for f in corridor()
    ]
    report, truth = run(tmp_path, distinct_csv, render, [(1.0, 1.0), (28.0, 1.0)])
    assert report.verdict == "unique match"
    (h,) = report.hypotheses
    assert h.n_outliers == 1 and "62903" not in h.matches
    assert h.pose.distance_to(truth) < 1e-3


def test_noisy_log_still_matches(tmp_path, distinct_csv) -> None:
    noisy = SyntheticParams(
        depth_noise=0.02,
        depth_noise_quad=0.005,
        pixel_noise=3.0,
        clip_boxes=True,
        odom_noise=(0.01, 0.02),
        detect_probability=0.8,
        false_positive_rate=0.05,
    )
    for seed in range(3):
        report, truth = run(
            tmp_path, distinct_csv, corridor(), [(1.0, 1.0), (30.0, 1.0)], params=noisy, seed=seed
        )
        assert report.outcome in (Verdict.UNIQUE, Verdict.AMBIGUOUS)
        if report.outcome is Verdict.UNIQUE:
            assert report.hypotheses[0].pose.distance_to(truth) < 0.3
        assert any(h.pose.distance_to(truth) < 0.3 for h in report.hypotheses)


def test_too_few_features_is_no_match_with_a_note(tmp_path, distinct_csv) -> None:
    report, _ = run(tmp_path, distinct_csv, corridor(), [(1.0, 1.0), (3.5, 1.0)])
    assert len(report.features) < 3
    assert report.verdict == "no consistent match" and report.outcome is Verdict.NONE
    assert any("at least 3" in n for n in report.notes)


def test_storey_auto_reports_the_storey(tmp_path) -> None:
    other = [
        SimFeature(f"L2-{i}", "door", x, 0.0, 0.0, 1.0) for i, x in enumerate([1.0, 6.0, 8.0, 15.0, 21.0])
    ]
    site = write_site_folder(tmp_path / "site", {"L1": (other, None), "L2": (corridor(), None)})
    report, truth = run(tmp_path, site, corridor(), [(1.0, 1.0), (22.0, 1.0)])
    assert report.storeys == ["L1", "L2"]
    assert report.verdict == "unique match" and report.storey == "L2" and report.hypotheses[0].storey == "L2"
    only_l1, _ = run(tmp_path, site, corridor(), [(1.0, 1.0), (22.0, 1.0)], storey="L1")
    assert only_l1.outcome is Verdict.NONE and only_l1.storeys == ["L1"]


def test_identical_storeys_are_ambiguous(tmp_path) -> None:
    site = write_site_folder(
        tmp_path / "site", {"L1": (corridor(), None), "L2": (corridor(first_id=80000), None)}
    )
    report, truth = run(tmp_path, site, corridor(), [(1.0, 1.0), (22.0, 1.0)])
    assert report.verdict == "2 hypotheses" and report.storey is None
    assert sorted(h.storey for h in report.hypotheses) == ["L1", "L2"]


def test_rectification_with_walls(tmp_path) -> None:
    walls = np.array([[0.0, 0.0, 40.0, 0.0, 0.0, 1.0], [0.0, 2.0, 40.0, 2.0, 0.0, -1.0]])
    site = write_site_folder(tmp_path / "site", {"L1": (corridor(), walls)})
    # the robot hugs the bottom wall at 0.3 m, closer than d_thre = 0.5 m
    report, truth = run(tmp_path, site, corridor(), [(1.0, 0.3), (24.0, 0.3)], d_thre=0.5)
    h = report.hypotheses[0]
    assert h.pose.distance_to(truth) < 1e-3 and h.rectified
    r = h.rectified_pose
    assert r.y == pytest.approx(0.5, abs=1e-9)  # out to the clearance line
    last = report.features[max(i for i, m in enumerate(h.matches) if m is not None)]
    bim = {f.id: f for f in corridor()}[h.matches[last.index]]
    d_o = math.hypot(last.x - report.odom_pose.x, last.y - report.odom_pose.y)
    assert math.hypot(r.x - bim.x, r.y - bim.y) == pytest.approx(d_o, abs=1e-9)  # Eq. 17's second constraint
    clear, _ = run(tmp_path, site, corridor(), [(1.0, 1.0), (24.0, 1.0)], d_thre=0.5)
    assert (
        not clear.hypotheses[0].rectified and clear.hypotheses[0].rectified_pose == clear.hypotheses[0].pose
    )


def test_feature_records_of_an_aggregating_robot(tmp_path, distinct_csv) -> None:
    from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
    from initcli.io.detection_log import FeatureRecord, Meta, Odom

    start = Pose2D(30.0, 1.0, math.pi)  # walking west from x = 30
    bim = {f.id: f for f in corridor()}
    seen = ["62925", "62905", "62924", "62904", "62923"]  # doors at 27 (top), 29.5, 20 (top), 24, 14.5 (top)
    records = [Meta(DEFAULT_CAMERA, DEFAULT_MOUNT)]
    for k, fid in enumerate(seen):
        p = start.apply_inverse(np.array([bim[fid].x, bim[fid].y]))
        records.append(Odom(float(k), 2.0 * k, 0.0, 0.0))
        records.append(FeatureRecord(float(k) + 0.5, "DOOR", float(p[0]), float(p[1])))
    records.append(Odom(10.0, 15.0, 0.0, 0.0))
    write_log(tmp_path / "features.jsonl", records)
    log, site = read_log(tmp_path / "features.jsonl"), load_site(distinct_csv)
    report = match_log(log, site, MatchOptions(max_outliers=0), ClassMap())
    assert report.verdict == "unique match"
    assert report.hypotheses[0].matches == seen
    assert all(f.given for f in report.features)
    assert report.hypotheses[0].pose.distance_to(start * Pose2D(15.0, 0.0, 0.0)) < 1e-6


def test_three_detections_with_a_false_one_are_never_a_wrong_unique_match(tmp_path) -> None:
    """Lifts L1, L2, L3 in a row and a door D above L1-L2. The robot sees L2, L3 and a poster placed
    above L2-L3 exactly as D is above L1-L2: the paper's algorithm (no outliers) finds the one full
    match (L1, L2, D), a wrong unique match; with --max-outliers 1 the alternative "the door was
    false" (L2, L3, -) is enumerated and the verdict is ambiguous."""
    from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
    from initcli.io.detection_log import FeatureRecord, Meta, Odom

    feats = [
        SimFeature("L1", "lift", 0.0, 0.0, 0.0, 1.0),
        SimFeature("L2", "lift", 3.0, 0.0, 0.0, 1.0),
        SimFeature("L3", "lift", 6.0, 0.0, 0.0, 1.0),
        SimFeature("D", "door", 1.0, 4.0, 0.0, -1.0),
        SimFeature("S", "stairs", 20.0, 2.0, -1.0, 0.0),
    ]
    csv = table1_csv(tmp_path / "lifts.csv", feats)
    records = [Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), Odom(0.0, 0.0, 0.0, 0.0)]
    for t, (cls, x, y) in enumerate([("lift", 3.0, 0.0), ("lift", 6.0, 0.0), ("door", 4.0, 4.0)], start=1):
        records.append(FeatureRecord(float(t), cls, x - 4.5, y - 2.0))  # odom frame = BIM shifted
    records.append(Odom(5.0, 0.0, 0.0, 0.0))
    write_log(tmp_path / "three.jsonl", records)
    log, site = read_log(tmp_path / "three.jsonl"), load_site(csv)
    paper = match_log(log, site, MatchOptions(max_outliers=0), ClassMap())
    assert paper.verdict == "unique match" and paper.hypotheses[0].matches == ["L1", "L2", "D"]  # wrong
    tolerant = match_log(log, site, MatchOptions(max_outliers=1, top=50), ClassMap())
    assert tolerant.outcome is Verdict.AMBIGUOUS
    assert ["L2", "L3", None] in [h.matches for h in tolerant.hypotheses]


def test_the_outlier_budget_grows_with_the_sequence(tmp_path, distinct_csv) -> None:
    """Three posters on one pass (a site as built): one outlier is not enough; the budget grows to a
    share of the features, and the fewest outliers that explain the sequence win."""
    posters = [SimFeature(f"poster-{x}", "door", x, 0.0, 0.0, 1.0) for x in (5.0, 13.5, 20.5)]
    waypoints = [(1.0, 1.0), (38.0, 1.0)]
    fixed, truth = run(tmp_path, distinct_csv, corridor(), waypoints, phantoms=posters, outlier_share=0.0)
    assert not any(h.pose.distance_to(truth) < 0.5 for h in fixed.hypotheses)
    assert fixed.outliers_allowed <= 1
    grown, truth = run(tmp_path, distinct_csv, corridor(), waypoints, phantoms=posters)
    assert grown.verdict == "unique match"
    (h,) = grown.hypotheses
    assert h.n_outliers == 3 and grown.outliers_allowed == 3
    assert h.pose.distance_to(truth) < 1e-3
    assert any("matched with 3" in n for n in grown.notes)


def test_a_revisited_feature_counts_once_toward_a_claim(tmp_path, distinct_csv) -> None:
    # Out along the corridor and back, heading drift (no distance error) keeping the filter from
    # merging the second sighting of each door with the first: the doors are matched again
    # (revisits), but a claim weighs each BIM feature once.
    waypoints = [(1.0, 1.0), (30.0, 1.0), (30.5, 1.4), (2.0, 1.4)]
    params = SyntheticParams(odom_noise=(0.0, 0.06))
    report, _ = run(tmp_path, distinct_csv, corridor(), waypoints, params=params, seed=5)
    assert report.verdict == "unique match"
    (h,) = report.hypotheses
    matched = [m for m in h.matches if m is not None]
    assert len(matched) > len(set(matched))  # revisits among the matches
    assert report.weighted_inliers(h) == len(set(matched)) < h.n_inliers
