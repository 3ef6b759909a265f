"""Whole initialisation sessions on the simulated robot (bim-init run)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.io.detection_log import read_log
from initcli.match.pipeline import MatchOptions, run_match
from tests.helpers import SAMPLES, replayed_claim

runner = CliRunner()


# Fixed corridor starts (BIM frame, yaw in degrees) and seeds.
STARTS = {
    "block_a": ("10.0,11.0,0", 3),
    "block_b": ("20.0,11.0,180", 2),
    "ntu_hallway": ("50.0,10.0,0", 4),
}


def write_config(tmp_path: Path, name: str, **sections) -> Path:
    doc = yaml.safe_load((SAMPLES / f"{name}.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / f"{name}.ifc")
    for section, values in sections.items():
        doc.setdefault(section, {}).update(values)
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def run(tmp_path: Path, config: Path, *extra: str, out: str = "out"):
    result = runner.invoke(
        app, ["run", "--config", str(config), "--out", str(tmp_path / out), "--quiet", *extra]
    )
    summary = tmp_path / out / "summary.json"
    return result, (json.loads(summary.read_text()) if summary.exists() else None)


# Random starts the 100-start evaluation once failed on, each for a different reason: odometry
# drift left no consistent hypothesis (ntu 1), a worker beside a material stack blocked the
# corridor (block_a 57), the bug algorithm followed a stack the wrong way round (block_b 16), the
# particle filter settled on the far side of a wall (block_b 35) or drifted off a good coarse pose
# (block_b 38).
HARD_SEEDS = [("ntu_hallway", 1), ("block_a", 57), ("block_b", 16), ("block_b", 35), ("block_b", 38)]


@pytest.mark.parametrize("name", sorted(STARTS))
def test_session_converges_from_a_fixed_start(tmp_path, name):
    start, seed = STARTS[name]
    result, doc = run(tmp_path, write_config(tmp_path, name), "--start", start, "--seed", str(seed))
    assert result.exit_code == 0, result.output
    assert doc["success"] and doc["reason"].startswith("initialised")
    assert doc["error_translation_m"]["coarse"] <= 0.3 and doc["error_rotation_deg"]["coarse"] <= 5.0
    assert doc["error_translation_m"]["fine"] <= 0.15 and doc["error_rotation_deg"]["fine"] <= 2.0
    assert doc["features_detected"] >= 3 and doc["distance_coarse_m"] <= doc["distance_total_m"]
    assert {p.name for p in (tmp_path / "out").iterdir()} >= {"session.jsonl", "summary.json", "report.png"}


def test_a_claim_held_back_by_its_rivals_is_late_but_not_wrong(tmp_path):
    """ntu_hallway from (30, 10, 0), seed 4, ideal world: the early claim on few features has a rival
    that passes the checks once alpha is 1.5 times wider, so the session drives on and claims later
    (24 m, fine error 0.10 m with active exploration off; 40 m and 0.69 m with it on); whatever the
    pose, never confidently wrong (2 m, 30 degrees)."""
    result, doc = run(
        tmp_path, write_config(tmp_path, "ntu_hallway"), "--start", "30.0,10.0,0", "--seed", "4"
    )
    assert result.exit_code == 0, result.output
    assert (
        doc["success"]
        and doc["error_translation_m"]["fine"] < 2.0
        and doc["error_rotation_deg"]["fine"] < 30.0
    )
    notes = [
        json.loads(line).get("why", "")
        for line in (tmp_path / "out" / "session.jsonl").read_text().splitlines()
    ]
    assert any("pass the checks too" in n for n in notes)


def test_same_seed_same_session(tmp_path):
    config = write_config(tmp_path, "block_b")
    run(tmp_path, config, "--seed", "5", out="a")
    run(tmp_path, config, "--seed", "5", out="b")
    assert (tmp_path / "a" / "session.jsonl").read_bytes() == (tmp_path / "b" / "session.jsonl").read_bytes()
    run(tmp_path, config, "--seed", "6", out="c")
    assert (tmp_path / "a" / "session.jsonl").read_bytes() != (tmp_path / "c" / "session.jsonl").read_bytes()


def test_log_replays_to_the_coarse_verdict_and_pose(tmp_path):
    """``bim-init match`` on the session's log finds what the session claimed: the unique match, or
    the hypothesis the lidar along the path favours, with the session's matches and coarse pose."""
    start, seed = STARTS["block_a"]
    _, doc = run(tmp_path, write_config(tmp_path, "block_a"), "--start", start, "--seed", str(seed))
    log_path, site_dir = tmp_path / "out" / "session.jsonl", tmp_path / "out" / "site"
    best = replayed_claim(log_path, site_dir, run_match(log_path, site_dir, MatchOptions()))
    assert best.matches == doc["matched_ids"]
    # The log's last odom record is later than the coarse decision (fine tuning continued):
    # the hypothesis' odom->BIM transform must be the session's.
    log = read_log(tmp_path / "out" / "session.jsonl")
    coarse = next(r for r in log.records if type(r).__name__ == "State" and r.data.get("state") == "coarse")
    odom_then = [o for o in log.odom if o.t <= coarse.t][-1].pose
    replayed = best.transform * odom_then
    pose = doc["coarse_pose"]
    assert math.hypot(replayed.x - pose["x"], replayed.y - pose["y"]) < 0.01
    assert abs(math.degrees(replayed.yaw - pose["yaw"])) < 0.5


@pytest.mark.parametrize("active", [True, False])
def test_ambiguous_start_triggers_active_exploration_when_it_is_on(tmp_path, active):
    start, seed = STARTS["ntu_hallway"]
    config = write_config(tmp_path, "ntu_hallway", exploration={"active": active})
    _, doc = run(tmp_path, config, "--start", start, "--seed", str(seed))
    log = read_log(tmp_path / "out" / "session.jsonl")
    states = [r.data.get("state") for r in log.records if type(r).__name__ == "State"]
    hypotheses = [r.data for r in log.records if type(r).__name__ == "HypothesesRecord"]
    assert any(1 < h["count"] < 40 for h in hypotheses)  # fewer than m_thre: active exploration's case
    if active:
        assert "active" in states and doc["active_explorations"] >= 1
    else:  # wall following only
        assert "active" not in states and doc["active_explorations"] == 0


@pytest.mark.parametrize(
    ("name", "start", "sim", "matching"),
    [
        ("block_a", "10.0,11.5,90", {}, {}),  # facing the corridor wall at 0.4 m
        ("block_a", "0.8,11.0,180", {}, {}),  # at the dead end of the corridor, facing it
        # Heavy clutter, the paper's alpha: at 0.8 this start stays ambiguous for 150 m (its one
        # unique match, turned half round, is rejected by the scan fit); the explorer is the subject.
        ("block_b", "20.0,11.0,0", {"clutter": 0.4, "people": 6}, {"alpha": 0.5}),
    ],
)
def test_hard_starts_initialise(tmp_path, name, start, sim, matching):
    """Each of these starts initialises (exit 0): the explorer backs off the wall it faces, turns
    round at the dead end, and gets through the heavy clutter; in the clutter fine tuning reaches
    its distance limit before the covariance threshold but the pose is already good, so the
    session still succeeds (the reason says so)."""
    config = write_config(tmp_path, name, sim=sim, matching=matching)
    result, doc = run(tmp_path, config, "--start", start, "--seed", "1")
    assert result.exit_code == 0, result.output
    assert doc is not None and doc["success"] is True
    assert doc["reason"].startswith("initialised")
    assert doc["error_translation_m"]["fine"] < 0.5


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        ({"camera": {"fx": "abc"}}, 'camera.fx: expected a number, got "abc"'),
        ({"lidar": {"beam": 3}}, "lidar.beam: unknown key"),
        ({"detector": {"kind": "yolo"}}, "detector.kind: expected one of simulated, onnx"),
        ({"robot": {"radius": -0.3}}, "robot.radius: -0.3 must be > 0"),
        ({"site": {"path": "missing.ifc"}}, "site.path"),
    ],
)
def test_config_errors_name_the_yaml_path(tmp_path, edit, fragment):
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / "block_a.ifc")
    for section, values in edit.items():
        doc[section].update(values)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(doc))
    result, _ = run(tmp_path, path)
    assert result.exit_code == 2
    assert fragment in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_invalid_yaml_names_the_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("site:\n  path: [unclosed\n")
    result, _ = run(tmp_path, path)
    assert result.exit_code == 2 and "bad.yaml:" in result.output


@pytest.mark.parametrize(("name", "seed"), HARD_SEEDS)
def test_starts_that_once_failed_now_initialise(tmp_path, name, seed):
    result, summary = run(tmp_path, write_config(tmp_path, name), "--seed", str(seed))
    assert result.exit_code == 0, summary and summary["reason"]
    assert summary["error_translation_m"]["fine"] < 0.3
    assert summary["error_rotation_deg"]["fine"] < 5.0  # block_b 38 keeps the rectified heading: 3.5 deg


def test_a_claim_by_the_lidar_along_the_path_replays_as_a_unique_match(tmp_path):
    """block_b under construction, seed 56: the session claims one of 11 hypotheses because the
    scans along its path fit only that one. ``bim-init match --json`` on the session's log says the
    same: unique (exit 0) by the lidar along the path, Algorithm 1's verdict (several hypotheses)
    kept in ``paper_verdict``, the claimed hypothesis first, each hypothesis with its ``track_fit``.
    The lidar registration is off: it claims this session before the doors do (a claim the log's
    features do not replay)."""
    config = write_config(
        tmp_path, "block_b", sim={"reality": "construction"}, registration={"enabled": False}
    )
    result, doc = run(tmp_path, config, "--seed", "56")
    assert result.exit_code == 0, result.output
    assert doc["success"]
    out = tmp_path / "out"
    match = runner.invoke(
        app, ["match", str(out / "session.jsonl"), "--site", str(out / "site"), "--json", "--top", "20"]
    )
    assert match.exit_code == 0, match.output
    report = json.loads(match.stdout)
    assert report["decided_by"] == "lidar along the path" and report["verdict"] == "unique match"
    assert re.fullmatch(r"\d+ hypotheses", report["paper_verdict"]) and report["n_hypotheses"] > 1
    assert report["hypotheses"][0]["matches"] == doc["matched_ids"]
    assert all(h["verification"]["track_fit"] for h in report["hypotheses"])
    # the console says the same whatever --top shows, with each shown hypothesis' checks
    args = ["match", str(out / "session.jsonl"), "--site", str(out / "site"), "--top", "1"]
    shown = runner.invoke(app, args)
    assert shown.exit_code == 0, shown.output
    assert "unique by the lidar along the path" in shown.stdout
    assert re.search(r"(pass|fail): missed \d+/\d+", shown.stdout)


def test_site_option_runs_on_an_extracted_site_without_extracting_again(tmp_path, site_a):
    """``--site`` overrides site.path (``make run`` runs on the site it has just extracted)."""
    config = write_config(tmp_path, "block_a")
    doc = yaml.safe_load(config.read_text())
    doc["site"]["path"] = "no_such_model.ifc"
    config.write_text(yaml.safe_dump(doc))
    start, seed = STARTS["block_a"]
    result, summary = run(tmp_path, config, "--site", str(site_a), "--start", start, "--seed", str(seed))
    assert result.exit_code == 0, result.output
    assert summary is not None and summary["success"]
    assert not (tmp_path / "out" / "site").exists()  # no extraction of its own
    result, _ = run(tmp_path, config, "--site", str(tmp_path / "nowhere"), out="out2")
    assert result.exit_code == 2 and "--site: " in result.output
    assert not (tmp_path / "out2").exists()
