"""A short evaluation on a real IFC model from other authors (sample_models/eval_real.yaml).

Skips cleanly when ../shared/ifc is absent; the whole campaign is ``make eval-real``.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.eval.config import load_eval_config
from tests.helpers import SAMPLES, SHARED_IFC


def test_eval_real_lists_every_storey_config_and_they_point_at_shared_models() -> None:
    config = load_eval_config(SAMPLES / "eval_real.yaml") if SHARED_IFC.is_dir() else None
    if config is None:
        pytest.skip(f"{SHARED_IFC} is absent (real IFC models from other authors)")
    names = [s.name for s in config.sites]
    assert len(names) == len(set(names)) >= 10
    assert "office_a_level_1" in names and "duplex_level_1" in names


def test_a_short_real_campaign_runs_and_claims_nothing_wrong(tmp_path: Path, shared_ifc_dir: Path) -> None:
    out = tmp_path / "eval"
    result = CliRunner().invoke(
        app,
        [
            "eval",
            "--config",
            str(SAMPLES / "eval_real.yaml"),
            "--sites",
            "duplex_level_1",
            "--starts",
            "2",
            "--methods",
            "bim,bim+pf",
            "--workers",
            "1",
            "--out",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert len(rows) == 4
    assert {r["site"] for r in rows} == {"duplex_level_1"}
    assert not any(r["confident_wrong"] for r in rows)
    assert (out / "table.md").is_file()
