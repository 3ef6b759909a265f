"""Every bim-init command walks a list of bad inputs: exit 2, one line on stderr, no traceback, and
nothing left behind (the folder the command ran in holds exactly what it held before).

The counts per command are in ``CASES`` (reported in the closing note of issue 10).
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml
from shapely.geometry import Polygon
from typer.testing import CliRunner

from bimtools.site.load import load_site
from initcli.cli.main import app
from initcli.io.log_writer import write_log
from initcli.sim.synthetic_log import SimFeature, make_log, path_from_waypoints

runner = CliRunner()
BINARY = bytes(range(256)) * 4  # NUL bytes and invalid UTF-8


def snapshot(root: Path) -> dict[str, int]:
    return {str(p.relative_to(root)): p.stat().st_size for p in root.rglob("*") if p.is_file()}


def assert_refused(root: Path, args: list[str], fragment: str) -> None:
    """Run bim-init in ``root``: exit 2, one stderr line containing ``fragment``, nothing new."""
    before = snapshot(root)
    here = os.getcwd()
    os.chdir(root)
    try:
        result = runner.invoke(app, [str(a) for a in args])
    finally:
        os.chdir(here)
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.exit_code == 2, (args, result.exit_code, result.output)
    assert len(lines) == 1, (args, result.stderr)
    assert lines[0].startswith("bim-init: error: "), lines[0]
    assert fragment in lines[0], (fragment, lines[0])
    assert "Traceback" not in result.output
    assert not isinstance(result.exception, Exception) or isinstance(result.exception, SystemExit)
    assert snapshot(root) == before, (args, set(snapshot(root)) ^ set(before))
    hidden = [p.name for p in root.rglob(".*") if p.name.startswith((".out", ".run", ".site"))]
    assert not hidden, hidden


# --- shared inputs ---------------------------------------------------------------------------------


@pytest.fixture()
def work(tmp_path: Path, site_a: Path) -> Path:
    """A folder with a valid site config (the extracted block_a), an eval config, a log, a file."""
    (tmp_path / "site.yaml").write_text(yaml.safe_dump({"site": {"path": str(site_a)}}))
    (tmp_path / "eval.yaml").write_text(yaml.safe_dump({"sites": [{"config": "site.yaml"}], "starts": 1}))
    (tmp_path / "binary.bin").write_bytes(BINARY)
    (tmp_path / "afile").write_text("not a folder\n")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("someone else's\n")
    features = [SimFeature(f"D{i}", "door", 2.0 + 4 * i, 0.0, 0.0, 1.0) for i in range(5)]
    t, path = path_from_waypoints([(1.0, 1.0), (18.0, 1.0)])
    write_log(tmp_path / "good.jsonl", make_log(features, t, path).records)
    return tmp_path


def config_with(work: Path, text: str, name: str = "bad.yaml") -> str:
    """The valid site config with ``text`` (YAML) appended."""
    (work / name).write_text((work / "site.yaml").read_text() + text)
    return name


def eval_with(work: Path, text: str, name: str = "bad_eval.yaml") -> str:
    (work / name).write_text((work / "eval.yaml").read_text() + text)
    return name


def wall_point(site_a: Path) -> tuple[float, float]:
    """A point inside a wall of block_a's simulated storey."""
    model = load_site(site_a)
    storey = max((s for s in model.storeys.values() if s.grid is not None), key=lambda s: len(s.features))
    walls = [o for o in storey.obstacles if o.ifc_class.startswith("IfcWall") and len(o.exterior) >= 3]
    p = Polygon(walls[0].exterior).representative_point()
    return p.x, p.y


def log_with(work: Path, edit: Callable[[list[dict]], None], name: str = "bad.jsonl") -> str:
    lines = [json.loads(line) for line in (work / "good.jsonl").read_text().splitlines() if line.strip()]
    edit(lines)
    (work / name).write_text("\n".join(json.dumps(d) for d in lines) + "\n")
    return name


def _first(kind: str, key: str, value: object) -> Callable[[list[dict]], None]:
    def edit(lines: list[dict]) -> None:
        next(d for d in lines if d.get("type") == kind)[key] = value

    return edit


# --- bim-init run ----------------------------------------------------------------------------------

RUN = [
    ("binary config", lambda w: ["--config", "binary.bin"], "not a text file"),
    ("latin-1 config", lambda w: ["--config", _latin1(w)], "not UTF-8"),
    ("config a folder", lambda w: ["--config", "other"], "is a folder"),
    ("YAML syntax", lambda w: ["--config", config_with(w, "camera: [1,\n")], "invalid YAML"),
    (
        "camera.fx nan",
        lambda w: ["--config", config_with(w, "camera:\n  fx: .nan\n")],
        "camera.fx: nan is not a finite",
    ),
    (
        "particles 1e12",
        lambda w: ["--config", config_with(w, "fine_tuning:\n  particles: 1000000000000\n")],
        "fine_tuning.particles: 1000000000000 is above the maximum 200000",
    ),
    (
        "particles 1e12 (YAML 1.2 form)",
        lambda w: ["--config", config_with(w, "fine_tuning:\n  particles: 1e12\n")],
        "is above the maximum 200000",
    ),
    (
        "lidar.fov 1e9",
        lambda w: ["--config", config_with(w, "lidar:\n  fov: 1e9\n")],
        "lidar.fov: 1000000000 is above the maximum 360",
    ),
    (
        "max_distance inf",
        lambda w: ["--config", config_with(w, "limits:\n  max_distance: .inf\n")],
        "limits.max_distance: inf is not a finite",
    ),
    (
        "max_time -inf",
        lambda w: ["--config", config_with(w, "limits:\n  max_time: -.inf\n")],
        "limits.max_time",
    ),
    (
        "radius negative",
        lambda w: ["--config", config_with(w, "robot:\n  radius: -0.3\n")],
        "robot.radius: -0.3 must be > 0",
    ),
    ("width huge", lambda w: ["--config", config_with(w, "camera:\n  width: 100000\n")], "camera.width"),
    (
        "image pixels",
        lambda w: ["--config", config_with(w, "camera:\n  width: 8000\n  height: 8000\n")],
        "pixels",
    ),
    ("beta nan", lambda w: ["--config", config_with(w, "matching:\n  beta: .nan\n")], "matching.beta"),
    (
        "miss_rate 2",
        lambda w: ["--config", config_with(w, "sim:\n  miss_rate: 2\n")],
        "sim.miss_rate: 2 is above the maximum 1",
    ),
    (
        "sim.seed negative",
        lambda w: ["--config", config_with(w, "sim:\n  seed: -3\n")],
        "sim.seed: -3 is below the minimum 0",
    ),
    (
        "odometry alpha inf",
        lambda w: ["--config", config_with(w, "sim:\n  odometry_noise:\n    alpha1: .inf\n")],
        "alpha1",
    ),
    (
        "t_thre inf",
        lambda w: ["--config", config_with(w, "exploration:\n  t_thre: .inf\n")],
        "exploration.t_thre",
    ),
    (
        "seed_sigma_yaw negative",
        lambda w: ["--config", config_with(w, "fine_tuning:\n  seed_sigma_yaw: -1\n")],
        "seed_sigma_yaw",
    ),
    (
        "camera pose huge",
        lambda w: ["--config", config_with(w, "camera:\n  pose:\n    z: 1e6\n")],
        "camera.pose.z",
    ),
    (
        "start nan in YAML",
        lambda w: ["--config", config_with(w, "sim:\n  start: [.nan, 0, 0]\n")],
        "sim.start.0: nan",
    ),
    (
        "sim.start outside",
        lambda w: ["--config", config_with(w, "sim:\n  start: [5000, 5000, 0]\n")],
        "outside the building",
    ),
    ("--seed -1", lambda w: ["--config", "site.yaml", "--seed", "-1"], "--seed: -1 is below the minimum 0"),
    ("--seed 2^40", lambda w: ["--config", "site.yaml", "--seed", str(2**40)], "--seed"),
    (
        "--start nan",
        lambda w: ["--config", "site.yaml", "--start", "nan,nan,0"],
        "--start x: nan is not a finite number",
    ),
    ("--start 1e300", lambda w: ["--config", "site.yaml", "--start", "1e300,0,0"], "--start x"),
    ("--start inf yaw", lambda w: ["--config", "site.yaml", "--start", "1,1,inf"], "--start yaw"),
    ("--start words", lambda w: ["--config", "site.yaml", "--start", "a,b"], "--start: expected x,y,yaw"),
    (
        "--start outside",
        lambda w: ["--config", "site.yaml", "--start", "5000,5000,0", "--out", "r"],
        "outside the building",
    ),
    (
        "--start in a wall",
        lambda w: ["--config", "site.yaml", "--start", _wall(w), "--out", "r"],
        "is inside IfcWall",
    ),
    ("--out a file", lambda w: ["--config", "site.yaml", "--out", "afile"], "--out afile: is a file"),
    ("--out under a file", lambda w: ["--config", "site.yaml", "--out", "afile/run"], "is a file"),
    ("--out foreign folder", lambda w: ["--config", "site.yaml", "--out", "other"], "pass --force"),
    (
        "--record under a file",
        lambda w: ["--config", "site.yaml", "--out", "r", "--record", "afile/s.mcap"],
        "is a file",
    ),
]


def _latin1(work: Path) -> str:
    (work / "latin1.yaml").write_bytes("site:\n  path: caf\xe9\n".encode("latin-1"))
    return "latin1.yaml"


def _wall(work: Path) -> str:
    site = yaml.safe_load((work / "site.yaml").read_text())["site"]["path"]
    x, y = wall_point(Path(site))
    return f"{x},{y},0"


@pytest.mark.parametrize("case", RUN, ids=[c[0] for c in RUN])
def test_run_refuses_bad_input(work: Path, case) -> None:
    _, args, fragment = case
    assert_refused(work, ["run", *args(work), "--quiet"], fragment)


# --- bim-init eval ---------------------------------------------------------------------------------

EVAL = [
    ("binary config", lambda w: ["--config", "binary.bin"], "not a text file"),
    (
        "max_error nan",
        lambda w: ["--config", eval_with(w, "failure:\n  max_error: .nan\n")],
        "failure.max_error: nan",
    ),
    (
        "wrong_error_deg huge",
        lambda w: ["--config", eval_with(w, "failure:\n  wrong_error_deg: 1e9\n")],
        "wrong_error_deg",
    ),
    (
        "amcl.particles -5",
        lambda w: ["--config", eval_with(w, "amcl:\n  particles: -5\n")],
        "amcl.particles: -5 is below the minimum 1",
    ),
    ("amcl.kld_err inf", lambda w: ["--config", eval_with(w, "amcl:\n  kld_err: .inf\n")], "amcl.kld_err"),
    ("markers.range nan", lambda w: ["--config", eval_with(w, "markers:\n  range: .nan\n")], "markers.range"),
    ("seed negative", lambda w: ["--config", eval_with(w, "seed: -1\n")], "seed: -1 is below the minimum 0"),
    ("starts 1e9", lambda w: ["--config", _eval_doc(w, {"starts": 10**9})], "starts"),
    (
        "start pose outside",
        lambda w: [
            "--config",
            _eval_doc(w, {"sites": [{"config": "site.yaml", "start_poses": [[5000, 5000, 0]]}]}),
        ],
        "sites.0.start_poses.0: (5000, 5000) is outside the building",
    ),
    (
        "start pose nan",
        lambda w: [
            "--config",
            _eval_doc(w, {"sites": [{"config": "site.yaml", "start_poses": [[float("nan"), 0, 0]]}]}),
        ],
        "nan",
    ),
    (
        "site config bad",
        lambda w: ["--config", _eval_doc(w, {"sites": [{"config": config_with(w, "lidar:\n  fov: 1e9\n")}]})],
        "lidar.fov",
    ),
    (
        "--sweep miss_rate=nan",
        lambda w: ["--config", "eval.yaml", "--sweep", "miss_rate=nan"],
        "--sweep miss_rate: nan",
    ),
    ("--sweep alpha=-1", lambda w: ["--config", "eval.yaml", "--sweep", "alpha=-1"], "--sweep alpha"),
    ("--sweep people=1.5", lambda w: ["--config", "eval.yaml", "--sweep", "people=1.5"], "whole numbers"),
    (
        "--sweep odometry_drift=inf",
        lambda w: ["--config", "eval.yaml", "--sweep", "odometry_drift=inf"],
        "odometry_drift",
    ),
    (
        "--starts 0",
        lambda w: ["--config", "eval.yaml", "--starts", "0"],
        "--starts: 0 is below the minimum 1",
    ),
    ("--workers 0", lambda w: ["--config", "eval.yaml", "--workers", "0"], "--workers"),
    ("--out a file", lambda w: ["--config", "eval.yaml", "--out", "afile"], "--out afile: is a file"),
    ("--out foreign folder", lambda w: ["--config", "eval.yaml", "--out", "other"], "pass --force"),
    (
        "--resume binary results",
        lambda w: ["--config", "eval.yaml", "--out", _results(w, BINARY), "--resume"],
        "results.jsonl",
    ),
    (
        "--resume typed record",
        lambda w: [
            "--config",
            "eval.yaml",
            "--out",
            _results(w, b'{"site": [1], "start": 0, "method": "bim", "success": true, "reason": "x"}\n'),
            "--resume",
        ],
        "'site': expected str",
    ),
    (
        "--resume nan record",
        lambda w: [
            "--config",
            "eval.yaml",
            "--out",
            _results(
                w,
                b'{"site": "s", "start": 0, "method": "bim", "success": true, "reason": "x", '
                b'"distance_m": NaN}\n',
            ),
            "--resume",
        ],
        "distance_m",
    ),
]


def _eval_doc(work: Path, doc: dict) -> str:
    merged = {**yaml.safe_load((work / "eval.yaml").read_text()), **doc}
    (work / "doc_eval.yaml").write_text(yaml.safe_dump(merged))
    return "doc_eval.yaml"


def _results(work: Path, data: bytes) -> str:
    (work / "old").mkdir(exist_ok=True)
    (work / "old" / "results.jsonl").write_bytes(data)
    return "old"


@pytest.mark.parametrize("case", EVAL, ids=[c[0] for c in EVAL])
def test_eval_refuses_bad_input(work: Path, case) -> None:
    _, args, fragment = case
    argv = args(work)
    assert_refused(work, ["eval", *argv, *([] if "--workers" in argv else ["--workers", "1"])], fragment)


# --- bim-init match --------------------------------------------------------------------------------

MATCH = [
    ("binary --site csv", lambda w, s: ["good.jsonl", "--site", "binary.bin"], "not a text file"),
    (
        "site folder with binary features.csv",
        lambda w, s: ["good.jsonl", "--site", _binary_site(w, s)],
        "features.csv",
    ),
    ("features.csv X 1e300", lambda w, s: ["good.jsonl", "--site", _csv(w, "1e300")], "column X"),
    ("features.csv X nan", lambda w, s: ["good.jsonl", "--site", _csv(w, "nan")], "column X"),
    ("binary log", lambda w, s: ["binary.bin", "--site", str(s)], "not a text file"),
    ("odometry x 1e300", lambda w, s: [log_with(w, _first("odom", "x", 1e300)), "--site", str(s)], "'x'"),
    ("odometry t huge", lambda w, s: [log_with(w, _first("odom", "t", 1e300)), "--site", str(s)], "'t'"),
    ("detection depth huge", lambda w, s: [log_with(w, _depth(1e9)), "--site", str(s)], "depth"),
    ("NaN literal in log", lambda w, s: [_nan_log(w), "--site", str(s)], "finite"),
    (
        "--alpha nan",
        lambda w, s: ["good.jsonl", "--site", str(s), "--alpha", "nan"],
        "--alpha: nan is not a finite",
    ),
    ("--alpha inf", lambda w, s: ["good.jsonl", "--site", str(s), "--alpha", "inf"], "--alpha"),
    ("--beta 1e9", lambda w, s: ["good.jsonl", "--site", str(s), "--beta", "1e9"], "--beta"),
    (
        "--score-threshold 2",
        lambda w, s: ["good.jsonl", "--site", str(s), "--score-threshold", "2"],
        "--score-threshold",
    ),
    (
        "--max-outliers 100",
        lambda w, s: ["good.jsonl", "--site", str(s), "--max-outliers", "100"],
        "--max-outliers",
    ),
    (
        "--drift-window inf",
        lambda w, s: ["good.jsonl", "--site", str(s), "--drift-window", "inf"],
        "--drift-window",
    ),
    (
        "--edge-margin nan",
        lambda w, s: ["good.jsonl", "--site", str(s), "--edge-margin", "nan"],
        "--edge-margin",
    ),
    ("--d-thre -1", lambda w, s: ["good.jsonl", "--site", str(s), "--d-thre", "-1"], "--d-thre"),
]


def _binary_site(work: Path, site: Path) -> str:
    import shutil

    target = work / "binsite"
    shutil.copytree(site, target)
    (target / "features.csv").write_bytes(BINARY)
    return "binsite"


def _csv(work: Path, x: str) -> str:
    (work / "t1.csv").write_text(f"ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\nD1,Doors,{x},0,0,1,1,2\n")
    return "t1.csv"


def _depth(value: float) -> Callable[[list[dict]], None]:
    def edit(lines: list[dict]) -> None:
        rec = next(d for d in lines if d.get("type") == "detections" and d.get("objects"))
        rec["objects"][0]["depth"] = value

    return edit


def _nan_log(work: Path) -> str:
    text = (work / "good.jsonl").read_text()
    lines = text.splitlines()
    i = next(k for k, line in enumerate(lines) if json.loads(line).get("type") == "odom")
    d = json.loads(lines[i])
    d["y"] = "__NAN__"
    lines[i] = json.dumps(d).replace('"__NAN__"', "NaN")
    (work / "nan.jsonl").write_text("\n".join(lines) + "\n")
    return "nan.jsonl"


@pytest.mark.parametrize("case", MATCH, ids=[c[0] for c in MATCH])
def test_match_refuses_bad_input(work: Path, site_a: Path, case) -> None:
    _, args, fragment = case
    assert_refused(work, ["match", *args(work, site_a)], fragment)


# --- bim-init detector -----------------------------------------------------------------------------

DETECTOR = [
    (
        "eval --data binary data.yaml",
        lambda w: ["eval", "default", "--data", _named(w, "data.yaml")],
        "not a text file",
    ),
    (
        "eval --data binary COCO",
        lambda w: ["eval", "default", "--data", _named(w, "coco.json")],
        "not a text file",
    ),
    ("eval --data nan in data.yaml", lambda w: ["eval", "default", "--data", _nan_data(w)], "nan"),
    (
        "eval --iou 2",
        lambda w: ["eval", "default", "--data", "x.yaml", "--iou", "2"],
        "--iou: 2 is above the maximum 1",
    ),
    ("eval --conf nan", lambda w: ["eval", "default", "--data", "x.yaml", "--conf", "nan"], "--conf"),
    ("eval --threads 0", lambda w: ["eval", "default", "--data", "x.yaml", "--threads", "0"], "--threads"),
    (
        "predict --out a file",
        lambda w: ["predict", "default", _image(w), "--out", "afile"],
        "--out afile: is a file",
    ),
    ("predict --conf nan", lambda w: ["predict", "default", _image(w), "--conf", "nan"], "--conf"),
    ("predict binary image", lambda w: ["predict", "default", "binary.bin"], "cannot read image"),
    ("synth --images 0", lambda w: ["synth", "--site", "x", "--out", "ds", "--images", "0"], "--images"),
    ("synth --size huge", lambda w: ["synth", "--site", "x", "--out", "ds", "--size", "100000x10"], "--size"),
    (
        "synth --val-fraction 1.5",  # 1 is a test set (docs/detector.md renders one)
        lambda w: ["synth", "--site", "x", "--out", "ds", "--val-fraction", "1.5"],
        "--val-fraction: 1.5 is above the maximum 1",
    ),
    ("synth --out a file", lambda w: ["synth", "--site", "x", "--out", "afile"], "is a file"),
    ("train --lr nan", lambda w: ["train", "--data", "x.yaml", "--lr", "nan"], "--lr"),
    ("train --epochs 0", lambda w: ["train", "--data", "x.yaml", "--epochs", "0"], "--epochs"),
    ("export --imgsz 1", lambda w: ["export", "model.pt", "--imgsz", "1"], "--imgsz"),
]


def _named(work: Path, name: str) -> str:
    (work / name).write_bytes(BINARY)
    return name


def _nan_data(work: Path) -> str:
    (work / "nan_data.yaml").write_text(
        "path: .\ntrain: images\nval: images\nnames: {0: door}\nscale: .nan\n"
    )
    return "nan_data.yaml"


def _image(work: Path) -> str:
    import cv2
    import numpy as np

    cv2.imwrite(str(work / "img.png"), np.zeros((64, 64, 3), np.uint8))
    return "img.png"


@pytest.mark.parametrize("case", DETECTOR, ids=[c[0] for c in DETECTOR])
def test_detector_refuses_bad_input(work: Path, case) -> None:
    _, args, fragment = case
    assert_refused(work, ["detector", *args(work)], fragment)


# --- bag2log, publish-pose, survey -----------------------------------------------------------------

OTHER = [
    ("bag2log -o a folder", lambda w, s: ["bag2log", "binary.bin", "-o", "other"], "is a folder"),
    ("bag2log -o under a file", lambda w, s: ["bag2log", "binary.bin", "-o", "afile/x.jsonl"], "is a file"),
    (
        "bag2log --rate nan",
        lambda w, s: ["bag2log", "binary.bin", "-o", "x.jsonl", "--rate", "nan"],
        "--rate",
    ),
    ("bag2log --rate 0", lambda w, s: ["bag2log", "binary.bin", "-o", "x.jsonl", "--rate", "0"], "--rate"),
    (
        "publish-pose binary summary",
        lambda w, s: ["publish-pose", "binary.bin", "--dry-run"],
        "not a text file",
    ),
    ("publish-pose NaN pose", lambda w, s: ["publish-pose", _summary(w, "NaN"), "--dry-run"], "nan"),
    ("publish-pose huge pose", lambda w, s: ["publish-pose", _summary(w, "1e300"), "--dry-run"], "pose.x"),
    ("publish-pose --port 0", lambda w, s: ["publish-pose", "x.json", "--port", "0"], "--port"),
    ("publish-pose missing", lambda w, s: ["publish-pose", "missing.json", "--dry-run"], "No such file"),
    ("survey --spacing nan", lambda w, s: ["survey", str(s), "--spacing", "nan"], "--spacing"),
    ("survey --spacing 0", lambda w, s: ["survey", str(s), "--spacing", "0"], "--spacing"),
    ("survey --headings 0", lambda w, s: ["survey", str(s), "--headings", "0"], "--headings"),
    ("survey --landmarks 5", lambda w, s: ["survey", str(s), "--landmarks", "5"], "--landmarks"),
    ("survey --workers 0", lambda w, s: ["survey", str(s), "--workers", "0"], "--workers"),
    ("survey --out a file", lambda w, s: ["survey", str(s), "--out", "afile"], "is a file"),
    ("survey --out foreign folder", lambda w, s: ["survey", str(s), "--out", "other"], "pass --force"),
    (
        "survey --config binary",
        lambda w, s: ["survey", str(s), "--config", "binary.bin", "--out", "sv"],
        "not a text file",
    ),
    (
        "survey --config nan",
        lambda w, s: ["survey", str(s), "--config", config_with(w, "camera:\n  fx: .nan\n"), "--out", "sv"],
        "camera.fx",
    ),
    (
        "survey binary features.csv",
        lambda w, s: ["survey", _binary_site(w, s), "--out", "sv"],
        "features.csv",
    ),
]


def _summary(work: Path, x: str) -> str:
    (work / "summary.json").write_text(
        '{"success": true, "reason": "ok", "pose": {"x": ' + x + ', "y": 0, "yaw_deg": 0}}'
    )
    return "summary.json"


@pytest.mark.parametrize("case", OTHER, ids=[c[0] for c in OTHER])
def test_other_commands_refuse_bad_input(work: Path, site_a: Path, case) -> None:
    _, args, fragment = case
    assert_refused(work, args(work, site_a), fragment)


CASES = {
    "run": len(RUN),
    "eval": len(EVAL),
    "match": len(MATCH),
    "detector": len(DETECTOR),
    "bag2log": sum(c[0].startswith("bag2log") for c in OTHER),
    "publish-pose": sum(c[0].startswith("publish-pose") for c in OTHER),
    "survey": sum(c[0].startswith("survey") for c in OTHER),
}
