"""The session config's ``detector.classes`` mapping reaches matching (an IFC extracted on the fly)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import yaml
from typer.testing import CliRunner

import initcli.sim.build as setup
from bimtools.site.load import load_site
from initcli.cli.main import app
from initcli.io.detection_log import read_log
from tests.helpers import SAMPLES


def test_detector_class_mapping_of_site_yaml_reaches_matching(tmp_path: Path, monkeypatch) -> None:
    # A detector that calls doors "Tür"; the site (block_a.ifc, extracted into the run's work folder,
    # where no site.yaml lies) names them Door. Only site.yaml's detector.classes relates the two.
    plain = setup.sim_features_from_bim

    def german_doors(features, cmap=None):
        return [dataclasses.replace(f, cls="Tür") if f.cls == "door" else f for f in plain(features, cmap)]

    monkeypatch.setattr(setup, "sim_features_from_bim", german_doors)
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text(encoding="utf-8"))
    doc["site"]["path"] = str(SAMPLES / "block_a.ifc")
    doc["detector"]["classes"] = {"Tür": "Door"}
    doc["registration"] = {"enabled": False}  # the doors decide, not the lidar
    config = tmp_path / "block_a.yaml"
    config.write_text(yaml.safe_dump(doc, allow_unicode=True), encoding="utf-8")
    out = tmp_path / "out"
    args = ["run", "--config", str(config), "--out", str(out), "--quiet", "--start", "10.0,11.0,0"]
    result = CliRunner().invoke(app, [*args, "--seed", "3"])
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["success"] and summary["reason"].startswith("initialised")
    seen = {o.cls for rec in read_log(out / "session.jsonl").detections for o in rec.objects}
    assert "Tür" in seen and "door" not in seen
    site = load_site(out / "site", with_maps=False)
    category = {f.id: f.category for s in site.storeys.values() for f in s.features}
    assert "Door" in {category[i] for i in summary["matched_ids"] if i is not None}
