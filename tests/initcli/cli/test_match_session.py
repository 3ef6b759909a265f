"""``bim-init match`` on a session's log over a site of two storeys, with no option: the session
recorded the storey it matched and its settings in the log's meta record, and the match takes them
(and says so), so the verdict and pose are the session's: a unique match by Algorithm 1, a claim by
the lidar registration, and a session that could not tell two alike storeys apart (no claim, and
the registration names the storey of the places alike). An option the user gives wins."""

from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from initcli.cli.main import app
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import read_log
from initcli.io.log_records import State
from tests.helpers import SAMPLES

runner = CliRunner()
LEVEL_2 = "Level 2"
RECORDED_NOTE = "storey Level 2 and settings from the session's log"


def two_storeys(first: Path, second: Path, out: Path) -> Path:
    """A site folder of ``first``'s storey and ``second``'s, the latter renamed Level 2 (3.5 m up):
    its features, walls and map appended, the manifest listing both."""
    shutil.copytree(first, out)
    (old,) = json.loads((second / "site.json").read_text())["storeys"]
    tag, src = LEVEL_2.replace(" ", "_"), old["name"].replace(" ", "_")
    rows = list(csv.reader((second / "features.csv").open()))
    storey, elevation = rows[0].index("Storey"), rows[0].index("Elevation")
    with (out / "features.csv").open("a", newline="") as handle:
        for row in rows[1:]:
            row[storey], row[elevation] = LEVEL_2, "3.5000"
            csv.writer(handle).writerow(row)
    walls = json.loads((out / "walls.geojson").read_text())
    for wall in json.loads((second / "walls.geojson").read_text())["features"]:
        wall["properties"]["storey"] = LEVEL_2
        walls["features"].append(wall)
    (out / "walls.geojson").write_text(json.dumps(walls))
    shutil.copy(second / f"map_{src}.pgm", out / f"map_{tag}.pgm")
    map_yaml = (second / f"map_{src}.yaml").read_text().replace(f"map_{src}.pgm", f"map_{tag}.pgm")
    (out / f"map_{tag}.yaml").write_text(map_yaml)
    manifest = json.loads((out / "site.json").read_text())
    manifest["storeys"].append(
        {**old, "name": LEVEL_2, "elevation": 3.5, "map_yaml": f"map_{tag}.yaml", "preview": None}
    )
    manifest["files"] += [f"map_{tag}.pgm", f"map_{tag}.yaml"]
    (out / "site.json").write_text(json.dumps(manifest, indent=2))
    return out


@pytest.fixture(scope="module")
def sites(site_a: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """block_a with block_b as Level 2 (two storeys unlike), and block_a twice (two alike)."""
    root = tmp_path_factory.mktemp("two_storeys")
    block_b = root / "block_b"
    write_site(block_b, extract_site(SAMPLES / "block_b.ifc"), preview=False)
    return {"ab": two_storeys(site_a, block_b, root / "ab"), "aa": two_storeys(site_a, site_a, root / "aa")}


def session(
    tmp: Path, sample: str, site: Path, storey: str, camera: bool, distance: float
) -> tuple[Path, dict]:
    """A simulated session (seed 1) of ``sample``'s config on ``site``: its log and summary."""
    doc = yaml.safe_load((SAMPLES / f"{sample}.site.yaml").read_text())
    doc["site"].update(path=str(site), storey=storey)
    doc["limits"]["max_distance"] = distance
    if not camera:
        doc["sim"].update(miss_rate=1.0, false_positives_per_minute=0.0)
    config = tmp / "site.yaml"
    config.write_text(yaml.safe_dump(doc))
    out = tmp / "out"
    run = runner.invoke(app, ["run", "--config", str(config), "--out", str(out), "--quiet", "--seed", "1"])
    assert run.exit_code in (0, 1), run.output
    return out / "session.jsonl", json.loads((out / "summary.json").read_text())


def match(log: Path, site: Path, *extra: str) -> tuple[int, dict]:
    result = runner.invoke(app, ["match", str(log), "--site", str(site), "--json", *extra])
    assert result.exit_code in (0, 3, 4), result.output
    return result.exit_code, json.loads(result.stdout)


def coarse_pose(log_path: Path, doc: dict) -> Pose2D:
    """The match's first hypothesis (at the log's last odom pose) carried back by odometry to the
    session's coarse claim."""
    log = read_log(log_path)
    claim = next(r for r in log.records if isinstance(r, State) and r.data.get("state") == "coarse")
    then = [o for o in log.odom if o.t <= claim.t][-1].pose
    p = doc["hypotheses"][0]["pose"]
    transform = Pose2D(p["x"], p["y"], p["yaw"]) * log.odom[-1].pose.inverse()
    return transform * then


def assert_same_pose(replayed: Pose2D, summary: dict) -> None:
    pose = summary["coarse_pose"]
    assert math.hypot(replayed.x - pose["x"], replayed.y - pose["y"]) < 0.05
    assert abs(math.degrees(replayed.yaw - pose["yaw"])) < 1.0


def test_a_unique_match_replays_with_no_option(sites, tmp_path: Path) -> None:
    """block_b's storey as Level 2 (site.storey Level 2), camera on: Algorithm 1's unique match."""
    log, summary = session(tmp_path, "block_b", sites["ab"], LEVEL_2, True, 60)
    assert summary["success"] and summary["storey"] == LEVEL_2 and summary["decided_by"] == "algorithm 1"
    meta = json.loads(log.read_text().splitlines()[0])
    assert meta["storey"] == LEVEL_2 and set(meta["settings"]) == {"matching", "registration"}
    assert meta["settings"]["matching"]["alpha"] == 0.8 and meta["settings"]["registration"]["enabled"]
    code, doc = match(log, sites["ab"])
    assert code == 0 and doc["verdict"] == "unique match" and doc["notes"][0] == RECORDED_NOTE
    best = doc["hypotheses"][0]
    assert best["storey"] == LEVEL_2 and best["matches"] == summary["matched_ids"]
    assert_same_pose(coarse_pose(log, doc), summary)
    # the console says so too, and a storey the user names wins over the log's
    shown = runner.invoke(app, ["match", str(log), "--site", str(sites["ab"])])
    assert f"note: {RECORDED_NOTE}" in shown.stdout
    code, doc = match(log, sites["ab"], "--storey", "Level 1")
    assert doc["storeys_searched"] == ["Level 1"] and doc["notes"][0] == "settings from the session's log"


def test_a_lidar_registration_claim_replays_with_no_option(sites, tmp_path: Path) -> None:
    """The same storey with the camera off: the session's lidar registration claim, replayed."""
    log, summary = session(tmp_path, "block_b", sites["ab"], LEVEL_2, False, 60)
    assert summary["success"] and summary["decided_by"] == "lidar registration"
    code, doc = match(log, sites["ab"])
    assert code == 0 and doc["verdict"] == "unique match" and doc["decided_by"] == "lidar registration"
    assert doc["notes"][0] == RECORDED_NOTE and doc["hypotheses"][0]["storey"] == LEVEL_2
    assert_same_pose(coarse_pose(log, doc), summary)
    # --no-registration given: no claim, whatever the log recorded
    code, doc = match(log, sites["ab"], "--no-registration")
    assert code == 4 and doc.get("decided_by") != "lidar registration"


@pytest.mark.parametrize(("camera", "exit_code"), [(True, 3), (False, 4)])
def test_two_alike_storeys_replay_to_no_claim(sites, tmp_path: Path, camera: bool, exit_code: int) -> None:
    """block_a twice, every storey matched: the session cannot tell the storeys apart and claims
    nothing; the match says the same (two hypotheses, one per storey; or no match), and the
    registration's reason names the storey of the places alike."""
    log, summary = session(tmp_path, "block_a", sites["aa"], "auto", camera, 30)
    assert not summary["success"] and summary["coarse_pose"] is None
    meta = json.loads(log.read_text().splitlines()[0])
    assert "storey" not in meta and "settings" in meta
    code, doc = match(log, sites["aa"])
    assert code == exit_code and doc["verdict"] != "unique match"
    assert doc["notes"][0] == "settings from the session's log; every storey searched, as it did"
    if camera:
        assert doc["verdict"] == "2 hypotheses"
        assert sorted(h["storey"] for h in doc["hypotheses"]) == ["Level 1", LEVEL_2]
    assert any("on storey Level 2" in n and "fit within" in n for n in doc["notes"]), doc["notes"]
