"""A whole session with detector kind onnx: rendered camera images, the shipped network, rendered depth."""

from __future__ import annotations

import json

import pytest
import yaml
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.detector import DEFAULT_MODEL
from tests.helpers import SAMPLES

pytestmark = pytest.mark.skipif(
    not DEFAULT_MODEL.exists(), reason="the default model has not been trained yet"
)


def test_onnx_session_completes(tmp_path):
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / "block_a.ifc")
    doc["detector"].update({"kind": "onnx", "model": "default"})
    doc["limits"]["max_distance"] = 60
    doc["camera"].update({"width": 320, "height": 240, "fx": 160, "fy": 160, "cx": 160, "cy": 120})
    doc["sim"].update({"clutter": 0.0, "people": 0})
    config = tmp_path / "onnx.yaml"
    config.write_text(yaml.safe_dump(doc))
    result = CliRunner().invoke(
        app,
        [
            "run",
            "--config",
            str(config),
            "--out",
            str(tmp_path / "out"),
            "--start",
            "30.0,11.0,180",
            "--quiet",
        ],
    )
    # The shipped network finds enough doors, lifts and stairs in the rendered images of block_a
    # for the session to initialise (exit 0) with a good pose.
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["success"] is True and summary["reason"] == "initialised"
    assert summary["error_translation_m"]["fine"] < 0.5
    lines = (tmp_path / "out" / "session.jsonl").read_text().splitlines()
    detections = [json.loads(line) for line in lines if '"type":"detections"' in line]
    assert detections and any(d["objects"] for d in detections), "the network detected something"
    objects = [o for d in detections for o in d["objects"]]
    assert {o["class"] for o in objects} <= {"door", "lift", "stairs"}
    assert all(o["depth"] is None or 0.1 < o["depth"] < 20 for o in objects)
