"""The survey marks the spaces a lidar alone cannot place (doors shut, the camera off): on the bundled
ntu_hallway the ring corridor is its own twin turned half round, on block_a it has none."""

from __future__ import annotations

import json

import jsonschema
import pytest
from typer.testing import CliRunner

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.site.load import load_site
from initcli.cli.main import app
from initcli.survey.plan import SurveyParams, plan_storey
from tests.helpers import SAMPLES, SCHEMAS


@pytest.fixture(scope="module")
def sites(tmp_path_factory: pytest.TempPathFactory):
    out = {}
    for name in ("ntu_hallway", "block_a"):
        folder = tmp_path_factory.mktemp(name) / "site"
        write_site(folder, extract_site(SAMPLES / f"{name}.ifc"), preview=False)
        out[name] = folder
    return out


def plan_of(site_dir):
    (storey,) = load_site(site_dir).storeys.values()
    return plan_storey(storey, SurveyParams(spacing=2.0, headings=1))


def test_the_ntu_ring_corridor_is_its_own_twin_turned_half_round(sites) -> None:
    plan = plan_of(sites["ntu_hallway"])
    assert plan.twin is None  # the storey as a whole is not self-similar: its rooms differ ...
    (corridor,) = [t for t in plan.lidar_twins if t.start_region]  # ... its corridor, doors shut, is
    assert corridor.turn_deg == 180.0
    # the twin of a point is the point turned about the middle of the 84 x 29 m floor
    assert (corridor.x + corridor.twin_x, corridor.y + corridor.twin_y) == pytest.approx(
        (84.0, 28.9), abs=0.2
    )
    assert plan.lidar_twin_start_share == 1.0


def test_block_a_s_corridor_has_no_lidar_twin(sites) -> None:
    plan = plan_of(sites["block_a"])
    assert not [t for t in plan.lidar_twins if t.start_region]
    assert plan.lidar_twin_start_share == 0.0
    assert plan.lidar_twins  # its offices, doors shut, are alike


def test_survey_json_and_the_terminal_name_the_lidar_twins(sites, tmp_path) -> None:
    out = tmp_path / "sv"
    args = ["survey", str(sites["ntu_hallway"]), "--out", str(out), "--spacing", "3", "--headings", "1"]
    result = CliRunner().invoke(app, [*args, "--landmarks", "0", "--workers", "1"])
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "survey.json").read_text())
    jsonschema.validate(doc, json.loads((SCHEMAS / "survey.schema.json").read_text()))
    (storey,) = doc["storeys"]
    assert storey["lidar_twin_start_share"] == 1.0
    assert storey["lidar_placed_share"] == 0.0  # and the registration along its loop places none
    assert storey["lidar_twin_tolerance_m"] == 0.25  # the session's verification.scan_tolerance
    (corridor,) = [t for t in storey["lidar_twins"] if t["start_region"]]
    assert corridor["turn_deg"] == 180.0
    assert corridor["x"] + corridor["twin_x"] == pytest.approx(84.0, abs=0.2)
    rooms = [t for t in storey["lidar_twins"] if not t["start_region"]]
    assert len(rooms) >= 16 and all(t["area_m2"] > 2.0 for t in rooms)  # the rooms behind the doors too
    assert "100 % of the start area has a lidar twin" in " ".join(result.output.split())
