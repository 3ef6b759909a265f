"""``bim-init eval`` end to end: a 2-site x 3-start x 4-method run, resume, a sweep, bad input."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.eval.tables import CSV_COLUMNS
from tests.helpers import SAMPLES

RESULT_KEYS = {
    "site",
    "start",
    "method",
    "success",
    "reason",
    "features",
    "distance_m",
    "error_translation_m",
    "error_rotation_deg",
    "confident_wrong",
    "seconds",
}


runner = CliRunner()


def site_config(tmp: Path, name: str, max_distance: float = 60.0) -> Path:
    """The sample's site config with an absolute model path and a shorter give-up distance (CI time)."""
    doc = yaml.safe_load((SAMPLES / f"{name}.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / f"{name}.ifc")
    doc["limits"]["max_distance"] = max_distance
    path = tmp / f"{name}.site.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def eval_config(tmp: Path, starts: int = 3, **extra) -> Path:
    doc = {
        "sites": [
            {"config": str(site_config(tmp, "block_a")), "paper": "BlockA"},
            {"config": str(site_config(tmp, "block_b")), "name": "blockB"},
        ],
        "starts": starts,
        "seed": 1,
        "failure": {"max_distance": 60},
        **extra,
    }
    path = tmp / "eval.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def invoke(*args: str):
    return runner.invoke(app, ["eval", *args])


def lines(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


@pytest.fixture(scope="module")
def full_run(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("eval")
    out = tmp / "out"
    result = invoke("--config", str(eval_config(tmp)), "--workers", "2", "--out", str(out))
    assert result.exit_code == 0, result.output
    return out


def test_full_run_writes_every_file_with_the_right_columns(full_run):
    rows = lines(full_run / "results.jsonl")
    assert len(rows) == 2 * 3 * 4
    assert all(RESULT_KEYS <= set(r) for r in rows)
    assert {(r["site"], r["start"], r["method"]) for r in rows} == {
        (s, k, m)
        for s in ("block_a", "blockB")
        for k in range(3)
        for m in ("bim", "bim+pf", "amcl", "markers")
    }
    for r in rows:
        assert r["distance_m"] >= 0 and r["seconds"] > 0
        if r["success"]:
            assert r["error_translation_m"] <= 5.0 and r["distance_m"] <= 60.0
    # one world per (site, start): every method starts from the same pose
    for site in ("block_a", "blockB"):
        for k in range(3):
            poses = {tuple(r["start_pose"]) for r in rows if r["site"] == site and r["start"] == k}
            assert len(poses) == 1
    with (full_run / "table.csv").open() as handle:
        table = list(csv.DictReader(handle))
    assert list(table[0]) == CSV_COLUMNS
    assert len(table) == 2 * 4
    for row in table:
        trials = [r for r in rows if r["site"] == row["site"] and r["method"] == row["method"]]
        assert int(row["trials"]) == 3
        assert int(row["successes"]) == sum(r["success"] for r in trials)
    a_pf = next(r for r in table if r["site"] == "block_a" and r["method"] == "bim+pf")
    assert a_pf["paper_environment"] == "BlockA" and float(a_pf["paper_error_translation_m"]) == 0.12
    b_pf = next(r for r in table if r["site"] == "blockB" and r["method"] == "bim+pf")
    assert b_pf["paper_environment"] == "" and b_pf["paper_error_translation_m"] == ""
    md = (full_run / "table.md").read_text()
    assert "## Table 2" in md and "## Table 3" in md and "(paper)" in md and "trials/min" in md
    for name in ("fig9.png", "fig12_block_a.png", "fig12_blockB.png"):
        assert (full_run / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bim_pf_localises_the_sample_blocks(full_run):
    rows = [r for r in lines(full_run / "results.jsonl") if r["method"] == "bim+pf"]
    assert sum(r["success"] for r in rows) >= 5
    assert not any(r["confident_wrong"] for r in rows)
    assert max(r["error_translation_m"] for r in rows if r["success"]) < 0.3


def test_resume_runs_only_the_missing_trials(full_run, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    kept = [line for line in (full_run / "results.jsonl").read_text().splitlines() if '"start":2' not in line]
    kept = [line for line in kept if '"method":"bim+pf"' not in line or '"start":0' not in line]
    partial = '{"site":"blockB","start":2,"meth'  # an interrupted write
    (out / "results.jsonl").write_text("\n".join(kept) + "\n" + partial)
    config = full_run.parent / "eval.yaml"
    result = invoke(
        "--config", str(config), "--workers", "1", "--out", str(out), "--resume", "--methods", "bim+pf"
    )
    assert result.exit_code == 0, result.output
    assert f"{len(kept)} trials" in result.output and "4 to run" in result.output
    rows = lines(out / "results.jsonl")
    assert [json.dumps(r, separators=(",", ":")) for r in rows[: len(kept)]] == kept
    added = rows[len(kept) :]
    assert sorted((r["site"], r["start"]) for r in added) == sorted(
        [("block_a", 0), ("block_a", 2), ("blockB", 0), ("blockB", 2)]
    )
    assert all(r["method"] == "bim+pf" for r in added)
    # the same seed gives the same trial
    before = {
        (r["site"], r["start"]): r for r in lines(full_run / "results.jsonl") if r["method"] == "bim+pf"
    }
    for r in added:
        assert r["start_pose"] == before[(r["site"], r["start"])]["start_pose"]
        assert r["distance_m"] == pytest.approx(before[(r["site"], r["start"])]["distance_m"])


def test_sweep_over_two_values_draws_its_plot(tmp_path):
    out = tmp_path / "out"
    config = eval_config(tmp_path, starts=1)
    result = invoke(
        "--config", str(config), "--workers", "1", "--out", str(out),
        "--sweep", "miss_rate=0,0.3", "--methods", "bim,markers", "--sites", "blockB",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    rows = lines(out / "results.jsonl")
    assert sorted((r["sweep_key"], r["sweep_value"], r["method"]) for r in rows) == [
        ("miss_rate", "0", "bim"),
        ("miss_rate", "0", "markers"),
        ("miss_rate", "0.3", "bim"),
        ("miss_rate", "0.3", "markers"),
    ]
    assert (out / "sweep_miss_rate.png").read_bytes()[:4] == b"\x89PNG"
    assert "## Robustness sweeps" in (out / "table.md").read_text()


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--methods", "bim,teleport"], "--methods"),
        (["--sweep", "warp=1,2"], "unknown key 'warp'"),
        (["--sweep", "alpha=0.4,wide"], "values must be numbers"),
        (["--sweep", "alpha"], "KEY=V1,V2"),
        (["--sites", "nowhere"], "no site 'nowhere'"),
    ],
)
def test_bad_options_exit_2_with_one_line(tmp_path, args, fragment):
    result = invoke("--config", str(eval_config(tmp_path)), "--out", str(tmp_path / "out"), *args)
    assert result.exit_code == 2
    assert fragment in result.output and "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert not (tmp_path / "out" / "results.jsonl").exists()


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        ({"starts": 0}, "starts: 0 is below the minimum 1"),
        ({"methods": ["bim", "gps"]}, "methods.1: expected one of"),
        ({"sites": [{"config": "missing.site.yaml"}]}, "sites.0.config:"),
        ({"sites": [{"path": "x"}]}, "sites.0.path: unknown key"),
        ({"sites": [{"name": "x"}]}, "sites.0.config: required"),
        ({"amcl": {"particle": 100}}, "amcl.particle: unknown parameter"),
        ({"failure": {"max_error": -1}}, "failure.max_error"),
    ],
)
def test_config_errors_name_the_yaml_path(tmp_path, edit, fragment):
    path = eval_config(tmp_path)
    doc = yaml.safe_load(path.read_text())
    doc.update(edit)
    path.write_text(yaml.safe_dump(doc))
    result = invoke("--config", str(path), "--out", str(tmp_path / "out"))
    assert result.exit_code == 2, result.output
    assert "eval.yaml" in result.output and fragment in result.output, result.output
    assert "Traceback" not in result.output


def test_results_file_with_a_broken_middle_line_is_refused(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.jsonl").write_text(
        '{"site":"a"\n{"site":"b","start":0,"method":"bim","success":true,"reason":""}\n'
    )
    result = invoke("--config", str(eval_config(tmp_path)), "--out", str(out), "--resume")
    assert result.exit_code == 2 and "results.jsonl:1: invalid JSON" in result.output


def test_bundled_eval_config_names_the_three_samples():
    from initcli.eval.config import load_eval_config

    config = load_eval_config(None)
    assert [s.name for s in config.sites] == ["ntu_hallway", "block_a", "block_b"]
    assert [s.paper for s in config.sites] == ["NTU", "BlockA", "BlockB"]
    assert config.methods == ("bim", "bim+pf", "amcl", "markers") and config.sites[0].starts == 100


def test_the_console_tables_fit_80_columns_and_say_what_they_leave_out() -> None:
    from rich.console import Console

    from initcli.cli.eval import _rich_table

    header = ["Site", "Method", "Success %", "(paper)", "Distance m", "(paper)", "Error m", "(paper)"]
    header += [
        "Error °",
        "(paper)",
        "Error m median / P95",
        "Confident wrong",
        "Trials",
        "Refused",
        "s / trial",
    ]
    row = ["block_a", "bim+pf", "96.0", "92.0", "23.61", "30.2", "0.041", "0.07", "0.52", "0.9"]
    row += ["0.032 / 0.091", "0", "100", "0", "12.5"]
    console = Console(width=80, record=True, color_system=None)
    console.print(_rich_table("Table 3", header, [row], console.width))
    text = console.export_text()
    assert "…" not in text and max(len(line) for line in text.splitlines()) <= 80
    assert "more column(s) in table.md" in text
    wide = Console(width=300, record=True, color_system=None)
    wide.print(_rich_table("Table 3", header, [row], wide.width))
    shown = wide.export_text()
    assert "more column(s)" not in shown and "Refused" in shown
