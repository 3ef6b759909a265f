"""Rooms, halls and open buildings (issue 31) end to end: worlds written by the sample IFC writer
(bimtools.samples.worlds), run through ``bim-init run``, ``eval`` and ``survey`` as a user would."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from bimtools.samples.worlds import world, write_plan
from initcli.cli.main import app
from tests.helpers import SAMPLES

runner = CliRunner()


def world_config(tmp_path: Path, name: str, **sim) -> Path:
    """A session config on test world ``name`` (written as IFC into ``tmp_path``), block_a's settings."""
    ifc = write_plan(world(name), tmp_path)
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    doc["site"]["path"] = ifc.name
    doc["sim"].update(sim)
    path = tmp_path / f"{name}.site.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def run(tmp_path: Path, config: Path, *extra: str, out: str = "out") -> tuple[object, dict | None]:
    result = runner.invoke(
        app, ["run", "--config", str(config), "--out", str(tmp_path / out), "--quiet", *extra]
    )
    summary = tmp_path / out / "summary.json"
    return result, (json.loads(summary.read_text()) if summary.exists() else None)


def truth_path(out: Path) -> list[tuple[float, float]]:
    rows = (json.loads(line) for line in (out / "session.jsonl").read_text().splitlines())
    return [(r["x"], r["y"]) for r in rows if r["type"] == "truth"]


@pytest.mark.parametrize("name", ["open_hall", "crane_hall"])
def test_a_hall_whose_facade_has_gates_initialises(tmp_path, name):
    """Gates stand open in the façade: the free space reaches the outside. Before floor slabs
    bounded it, the open hall's map had no free space at all and ``Circulation.of`` raised an argmax
    of an empty sequence (a traceback); now the hall initialises, within the building."""
    config = world_config(tmp_path, name)
    result, doc = run(tmp_path, config, "--seed", "1")
    assert result.exit_code == 0, result.output
    assert doc is not None and doc["success"], doc
    assert doc["error_translation_m"]["fine"] <= 0.3
    xs, ys = zip(*truth_path(tmp_path / "out"), strict=True)
    plan = world(name)
    x1 = max(c.x1 for c in plan.cells)
    y1 = max(c.y1 for c in plan.cells)
    assert min(xs) > 0.0 and max(xs) < x1 and min(ys) > 0.0 and max(ys) < y1  # never out of a gate


def test_eval_and_survey_on_an_open_hall(tmp_path):
    config = world_config(tmp_path, "open_hall")
    eval_config = tmp_path / "eval.yaml"
    eval_config.write_text(yaml.safe_dump({"sites": [{"config": config.name}], "starts": 2, "seed": 5}))
    result = runner.invoke(
        app,
        [
            "eval",
            "--config",
            str(eval_config),
            "--methods",
            "bim",
            "--workers",
            "1",
            "--out",
            str(tmp_path / "ev"),
        ],
    )
    assert result.exit_code == 0, result.output
    records = [json.loads(line) for line in (tmp_path / "ev" / "results.jsonl").read_text().splitlines()]
    assert len(records) == 2 and not any(r["confident_wrong"] for r in records)
    run(tmp_path, config, "--seed", "2", out="one")
    site = tmp_path / "one" / "site"
    result = runner.invoke(
        app,
        [
            "survey",
            str(site),
            "--out",
            str(tmp_path / "sv"),
            "--spacing",
            "4",
            "--headings",
            "1",
            "--workers",
            "1",
        ],
    )
    assert result.exit_code == 0, result.output
    (storey,) = json.loads((tmp_path / "sv" / "survey.json").read_text())["storeys"]
    # the hall's floor at a 4 m spacing (at most 13 x 5 positions): before slabs bounded it, none
    assert 30 <= storey["positions"] <= 65
