"""``bim-init match`` end to end: output, JSON schema, plot, exit codes and every bad-input case."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest
import yaml
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.io.log_writer import write_log
from initcli.sim.synthetic_floor import write_site_folder
from initcli.sim.synthetic_log import SimFeature, make_log, path_from_waypoints
from tests.helpers import SAMPLES, SCHEMAS

RESULT_SCHEMA = json.loads((SCHEMAS / "match_result.schema.json").read_text())


runner = CliRunner()


BOTTOM = [2.0, 7.5, 11.0, 17.3, 24.0, 29.5, 33.0, 38.0]


TOP = [4.0, 9.0, 14.5, 20.0, 27.0, 35.5]


FEATS = (
    [SimFeature(f"D{i}", "door", x, 0.0, 0.0, 1.0) for i, x in enumerate(BOTTOM)]
    + [SimFeature(f"T{i}", "door", x, 2.0, 0.0, -1.0) for i, x in enumerate(TOP)]
    + [
        SimFeature("L1", "lift", 40.0, 1.0, -1.0, 0.0, 1.1),
        SimFeature("S1", "stairs", 0.0, 1.0, 1.0, 0.0, 1.2),
    ]
)


CATEGORY = {"door": "Doors", "lift": "Lift", "stairs": "Stairs"}  # the paper's Table 1 names


TABLE1 = "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n" + "".join(
    f"{f.id},{CATEGORY[f.cls]},{f.x},{f.y},{f.norm_x},{f.norm_y},{f.width},{f.height}\n" for f in FEATS
)


PERIODIC = [SimFeature(f"P{i}", "door", 2.0 + 4 * i, 0.0, 0.0, 1.0) for i in range(20)] + [
    SimFeature(f"Q{i}", "door", 2.0 + 4 * i, 2.0, 0.0, -1.0) for i in range(20)
]


def invoke(*args: str):
    return runner.invoke(app, [str(a) for a in args])


def make(tmp: Path, name: str, render=FEATS, waypoints=((1.0, 1.0), (22.0, 1.0)), phantoms=()) -> Path:
    t, path = path_from_waypoints(list(waypoints))
    log = make_log(list(render), t, path, phantoms=list(phantoms))
    out = tmp / name
    write_log(out, log.records)
    return out


@pytest.fixture()
def table1(tmp_path: Path) -> Path:
    path = tmp_path / "table1.csv"
    path.write_text(TABLE1, encoding="utf-8")
    return path


@pytest.fixture()
def good_log(tmp_path: Path) -> Path:
    return make(tmp_path, "good.jsonl")


def assert_bad_input(result, *fragments: str) -> None:
    assert result.exit_code == 2, (result.exit_code, result.output)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("bim-init: error: ")
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    assert "Traceback" not in result.output


def test_unique_match_text_output(table1: Path, good_log: Path) -> None:
    result = invoke("match", good_log, "--site", table1)
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "Confirmed features" in out and "Hypotheses" in out
    assert "D1 T1 D2 T2 D3 T3 D4 T4" in out
    assert out.strip().splitlines()[-1].strip() == "unique match"


def test_json_document_follows_the_schema(table1: Path, good_log: Path) -> None:
    result = invoke("match", good_log, "--site", table1, "--json", "--pose-method", "paper")
    assert result.exit_code == 0
    doc = json.loads(result.stdout)
    jsonschema.validate(doc, RESULT_SCHEMA)
    assert doc["verdict"] == "unique match" and doc["exit_code"] == 0 and doc["storey"] == ""
    (h,) = doc["hypotheses"]
    assert len(h["matches"]) == len(doc["features"]) and all(isinstance(m, str) for m in h["matches"])
    assert h["pose"]["x"] == pytest.approx(22.0, abs=1e-3) and h["pose"]["y"] == pytest.approx(1.0, abs=1e-3)
    assert h["rectified_pose"] is None and h["confidence"] == pytest.approx(1.0)
    assert doc["pose_method"] == "paper"


def test_outlier_is_null_in_json(tmp_path: Path, table1: Path) -> None:
    poster = SimFeature("poster", "door", 13.0, 0.0, 0.0, 1.0)
    log = make(tmp_path, "fp.jsonl", waypoints=((1.0, 1.0), (26.0, 1.0)), phantoms=[poster])
    result = invoke("match", log, "--site", table1, "--json", "--max-outliers", "1")
    doc = json.loads(result.stdout)
    jsonschema.validate(doc, RESULT_SCHEMA)
    assert result.exit_code == 0 and doc["hypotheses"][0]["matches"].count(None) == 1
    strict = invoke("match", log, "--site", table1, "--json", "--max-outliers", "0", "--outlier-share", "0")
    assert strict.exit_code == 4 and json.loads(strict.stdout)["verdict"] == "no consistent match"


def test_ambiguous_exit_3(tmp_path: Path) -> None:
    csv = tmp_path / "periodic.csv"
    csv.write_text(
        "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n"
        + "".join(f"{f.id},Door,{f.x},{f.y},{f.norm_x},{f.norm_y},1.0,2.1\n" for f in PERIODIC)
    )
    log = make(tmp_path, "p.jsonl", render=PERIODIC, waypoints=((24.0, 1.0), (40.0, 1.0)))
    result = invoke("match", log, "--site", csv, "--top", "3")
    assert result.exit_code == 3
    last = result.stdout.strip().splitlines()[-1].strip()
    assert last.endswith(" hypotheses") and int(last.split()[0]) > 3
    doc = json.loads(invoke("match", log, "--site", csv, "--top", "3", "--json").stdout)
    jsonschema.validate(doc, RESULT_SCHEMA)
    assert len(doc["hypotheses"]) == 3 and doc["n_hypotheses"] == int(last.split()[0])
    assert doc["verdict"] == last
    confidences = [h["confidence"] for h in doc["hypotheses"]]
    assert confidences == sorted(confidences, reverse=True) or doc["hypotheses"][0]["outliers"] == 0


def test_no_match_exit_4(tmp_path: Path, table1: Path) -> None:
    other = [SimFeature(f"O{i}", "door", x, 0.0, 0.0, 1.0) for i, x in enumerate([1.0, 3.0, 9.5, 12.0, 19.0])]
    log = make(tmp_path, "other.jsonl", render=other, waypoints=((0.0, 1.0), (16.0, 1.0)))
    result = invoke("match", log, "--site", table1, "--max-outliers", "0", "--outlier-share", "0")
    assert result.exit_code == 4 and result.stdout.strip().splitlines()[-1].strip() == "no consistent match"


def test_plot(tmp_path: Path, table1: Path, good_log: Path) -> None:
    png = tmp_path / "out" / "hyp.png"
    result = invoke("match", good_log, "--site", table1, "--plot", png)
    assert result.exit_code == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_site_folder_with_walls_storeys_and_class_mapping(tmp_path: Path) -> None:
    import numpy as np

    walls = np.array([[0.0, 0.0, 40.0, 0.0, 0.0, 1.0], [0.0, 2.0, 40.0, 2.0, 0.0, -1.0]])
    other = [SimFeature(f"X{i}", "door", x, 0.0, 0.0, 1.0) for i, x in enumerate([1.0, 6.0, 8.0, 15.0])]
    site = write_site_folder(tmp_path / "site", {"Level 1": (other, None), "Level 2": (FEATS, walls)})
    (site / "site.yaml").write_text(
        "site:\n  path: .\ndetector:\n  classes:\n    gate: Door\n    Elevator Car: Lift\n"
    )
    renamed = [
        SimFeature(f.id, "gate" if f.cls == "door" else f.cls, f.x, f.y, f.norm_x, f.norm_y) for f in FEATS
    ]
    log = make(tmp_path, "gates.jsonl", render=renamed, waypoints=((1.0, 0.4), (22.0, 0.4)))
    result = invoke("match", log, "--site", site, "--json")
    doc = json.loads(result.stdout)
    jsonschema.validate(doc, RESULT_SCHEMA)
    assert (
        result.exit_code == 0
        and doc["storey"] == "Level 2"
        and doc["storeys_searched"] == ["Level 1", "Level 2"]
    )
    h = doc["hypotheses"][0]
    assert h["storey"] == "Level 2" and h["rectified"] and h["rectified_pose"]["y"] == pytest.approx(0.5)
    only = invoke("match", log, "--site", site, "--storey", "Level 1")
    assert only.exit_code == 4


def test_skip_bad(tmp_path: Path, table1: Path, good_log: Path) -> None:
    lines = good_log.read_text().splitlines()
    lines.insert(5, "{this is not json")
    lines.insert(9, '{"type":"odom","t":"late"}')
    broken = tmp_path / "broken.jsonl"
    broken.write_text("\n".join(lines) + "\n")
    assert_bad_input(invoke("match", broken, "--site", table1), "broken.jsonl:6:", "not valid JSON")
    result = invoke("match", broken, "--site", table1, "--skip-bad")
    assert result.exit_code == 0
    assert "skipped 2 malformed line(s)" in result.stderr


@pytest.mark.parametrize(
    ("content", "fragments"),
    [
        ("", ("empty log",)),
        ('{"type":"odom","t":0,"x":0,"y":0,"yaw":0}\n', ("missing meta record", ":1:")),
        (None, ("unsupported detection log version 2",)),
        ("not json at all\n", (":1:", "not valid JSON")),
    ],
)
def test_bad_logs(tmp_path: Path, table1: Path, good_log: Path, content, fragments) -> None:
    path = tmp_path / "bad.jsonl"
    if content is None:
        content = good_log.read_text().replace('"version":1', '"version":2', 1)
    path.write_text(content)
    assert_bad_input(invoke("match", path, "--site", table1), *fragments)


def test_unknown_class_names_are_listed(tmp_path: Path, table1: Path, good_log: Path) -> None:
    text = good_log.read_text().replace('"class":"door"', '"class":"window"', 3)
    text = text.replace('"class":"door"', '"class":"Person"', 1)
    path = tmp_path / "classes.jsonl"
    path.write_text(text)
    assert_bad_input(invoke("match", path, "--site", table1), "unknown class name(s)", "'Person'", "'window'")


def test_bad_sites_and_options(tmp_path: Path, table1: Path, good_log: Path) -> None:
    empty_dir = tmp_path / "nosite"
    empty_dir.mkdir()
    assert_bad_input(invoke("match", good_log, "--site", empty_dir), "no features.csv")
    assert_bad_input(invoke("match", good_log, "--site", tmp_path / "absent"), "no such file or folder")
    header_only = tmp_path / "header.csv"
    header_only.write_text("ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n")
    assert_bad_input(invoke("match", good_log, "--site", header_only), "no features")
    no_table1 = tmp_path / "wrong.csv"
    no_table1.write_text("ID,Kind,X\n1,Door,0\n")
    assert_bad_input(invoke("match", good_log, "--site", no_table1), "missing column")
    assert_bad_input(
        invoke("match", good_log, "--site", table1, "--storey", "Level 9"), "no storey 'Level 9'"
    )
    assert_bad_input(invoke("match", tmp_path / "absent.jsonl", "--site", table1), "no such file")
    assert_bad_input(invoke("match", good_log, "--site", table1, "--alpha", "-1"), "--alpha")
    assert_bad_input(invoke("match", good_log, "--site", table1, "--pose-method", "magic"), "--pose-method")
    missing = invoke("match", good_log)
    assert missing.exit_code == 2 and "Traceback" not in missing.output


def test_console_script_has_no_traceback(tmp_path: Path, table1: Path) -> None:
    exe = Path(sys.executable).with_name("bim-init")
    if not exe.exists():
        pytest.skip("bim-init is not installed in this environment")
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"type":"meta","version":1}\n')
    done = subprocess.run([exe, "match", bad, "--site", table1], capture_output=True, text=True)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.count("\n") == 1 and "bad.jsonl:1:" in done.stderr


# --- a ROS bag as the log: bag2log's options, errors naming the bag ---------------------------------


def _bag_and_site(tmp_path: Path) -> tuple[Path, Path]:
    from benchmarks._recordings import POINTS, make_recording, write

    bag = write(tmp_path, make_recording(numeric=True, layout="foxy"), "sqlite3", "foxy")
    rows = "".join(
        f"F{i},{CATEGORY[c]},{x + 10},{y + 5},0,1,1,2\n" for i, (c, (x, y, _)) in enumerate(POINTS.items())
    )
    site = tmp_path / "three.csv"
    site.write_text("ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n" + rows, encoding="utf-8")
    return bag, site


def test_a_bag_takes_bag2logs_options(tmp_path: Path) -> None:
    bag, site = _bag_and_site(tmp_path)
    options = ["--class-names", "door,lift,stairs", "--detections-topic", "/detections"]
    options += ["--odom-topic", "/odom", "--base-frame", "base_link", "--rate", "5"]
    result = invoke("match", bag, "--site", site, *options, "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["verdict"] == "unique match" and doc["hypotheses"][0]["matches"] == ["F0", "F1", "F2"]


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        ([], "(as a detection log): unknown class name(s) '0', '1', '2'"),  # numeric ids left unnamed
        (["--odom-topic", "/nope"], "no topic /nope (--odom-topic)"),
        (["--class-names", "door,1=lift"], "--class-names"),
    ],
)
def test_bag_errors_name_the_bag(tmp_path: Path, args: list[str], fragment: str) -> None:
    bag, site = _bag_and_site(tmp_path)
    result = invoke("match", bag, "--site", site, *args)
    assert_bad_input(result, fragment)
    if args != ["--class-names", "door,1=lift"]:
        assert str(bag) in result.stderr and "bim-init-bag2log-" not in result.stderr


@pytest.fixture(scope="module")
def symmetric_session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A simulated block_a session's log and site (the sample config, the random start of seed
    103): block_a is point-symmetric, and the doors this session saw fit two places."""
    tmp_path = tmp_path_factory.mktemp("symmetric")
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / "block_a.ifc")
    doc["registration"] = {"enabled": False}  # the lidar along the path decides, not a registration
    config = tmp_path / "block_a.yaml"
    config.write_text(yaml.safe_dump(doc))
    out = tmp_path / "session"
    result = runner.invoke(
        app, ["run", "--config", str(config), "--out", str(out), "--seed", "103", "--quiet"]
    )
    assert result.exit_code == 0, result.output
    return out / "session.jsonl", out / "site"


def _off(pose: dict, truth: dict) -> tuple[float, float]:
    turn = math.atan2(math.sin(pose["yaw"] - truth["yaw"]), math.cos(pose["yaw"] - truth["yaw"]))
    return math.hypot(pose["x"] - truth["x"], pose["y"] - truth["y"]), abs(math.degrees(turn))


def test_the_lidar_along_the_path_makes_a_symmetric_match_unique(tmp_path: Path, symmetric_session) -> None:
    """The session saw doors that two places fit (Algorithm 1 leaves 2 hypotheses), and claimed the
    one the scans along its path fit. ``match`` on its log says the same: unique (exit 0), decided
    by the lidar, the right place first; without the scans the log stays ambiguous (exit 3)."""
    log, site = symmetric_session
    result = invoke("match", log, "--site", site, "--json")
    doc = json.loads(result.stdout)
    jsonschema.validate(doc, RESULT_SCHEMA)
    assert doc["paper_verdict"].endswith(" hypotheses"), doc["paper_verdict"]  # the case under test
    assert result.exit_code == 0 and doc["verdict"] == "unique match"
    assert doc["decided_by"] == "lidar along the path"
    assert [h["rank"] for h in doc["hypotheses"]] == list(range(1, len(doc["hypotheses"]) + 1))
    metres, degrees = _off(doc["hypotheses"][0]["pose"], doc["truth"])
    assert metres < 0.5 and degrees < 5.0
    assert doc["hypotheses"][0]["verification"]["passed"]

    no_scans = tmp_path / "no_scans.jsonl"
    no_scans.write_text("".join(line for line in log.open() if '"type":"scan"' not in line))
    blind = invoke("match", no_scans, "--site", site, "--json")
    blind_doc = json.loads(blind.stdout)
    assert blind.exit_code == 3 and blind_doc["decided_by"] is None
    assert blind_doc["verdict"] == blind_doc["paper_verdict"] == doc["paper_verdict"]


def test_a_unique_match_the_lidar_refutes_is_not_claimed(symmetric_session) -> None:
    """Algorithm 1's one hypothesis is still checked: alone at the true place it stays unique; moved
    to a place where the scans do not fit the walls, the verdict is no consistent match (exit 4)."""
    from initcli.core.geometry.se2 import Pose2D
    from initcli.core.hypotheses.ranking import Verdict
    from initcli.match.pipeline import DECIDED_BY_PAPER, MatchOptions, run_match
    from initcli.verify.evidence import check_hypotheses

    log, site = symmetric_session

    def alone(moved: Pose2D):
        report = run_match(log, site, MatchOptions())
        h = (
            report.hypotheses[0]
            if _off(_pose(report.hypotheses[0].pose), _pose(report.truth))[0] < 1
            else report.hypotheses[1]
        )
        h = dataclasses.replace(h, pose=moved * h.pose, rectified_pose=None, rank=1)
        report.hypotheses, report.n_hypotheses = [h], 1
        report.decide(1)
        report.decided_by = DECIDED_BY_PAPER
        checks = check_hypotheses(log, site, report, False, 1)
        return report, checks

    kept, checks = alone(Pose2D(0.0, 0.0, 0.0))
    assert kept.outcome is Verdict.UNIQUE and kept.decided_by == DECIDED_BY_PAPER and checks[0].passed
    refused, checks = alone(Pose2D(0.0, 3.0, 0.0))  # 3 m across the corridor: into the walls
    assert not checks[0].passed
    assert refused.outcome is Verdict.NONE and refused.verdict == "no consistent match"
    assert refused.paper_verdict == "unique match" and refused.decided_by is None
    assert any("fails the checks" in n for n in refused.notes)


def _pose(p) -> dict:
    return {"x": p.x, "y": p.y, "yaw": p.yaw}


def test_each_outcome_maps_to_one_exit_code() -> None:
    """The library's outcome becomes the command's exit code in initcli.cli.exit_codes alone; bad
    input is bimkit's code 2, not a second definition."""
    from bimkit.errors import EXIT_BAD_INPUT
    from initcli.cli import exit_codes
    from initcli.core.hypotheses.ranking import Verdict

    assert [exit_codes.match_exit_code(Verdict.of(n)) for n in (0, 1, 2, 7)] == [4, 0, 3, 3]
    assert exit_codes.EXIT_BAD_INPUT is EXIT_BAD_INPUT and EXIT_BAD_INPUT == 2
    assert Verdict.UNIQUE == "unique match" and Verdict.NONE == "no consistent match"
