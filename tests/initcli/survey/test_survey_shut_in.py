"""The survey marks the rooms a robot would be shut in (issue 31): spaces closed off by their doors
that no feature faces, on survey.json and the map ("cannot initialise from here")."""

from __future__ import annotations

import json

import jsonschema
import pytest
from typer.testing import CliRunner

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.samples.worlds import world, write_plan
from bimtools.site.load import load_site
from initcli.cli.main import app
from initcli.survey.plan import SurveyParams, plan_storey
from tests.helpers import SCHEMAS


def storey_of(tmp_path, name):
    site_dir = tmp_path / f"{name}_site"
    write_site(site_dir, extract_site(write_plan(world(name), tmp_path)), preview=False)
    site = load_site(site_dir)
    (storey,) = site.storeys.values()
    return site_dir, storey


def bedroom(rooms):
    return [r for r in rooms if 7.0 < r.x < 12.0 and 0.0 < r.y < 6.0]


@pytest.mark.parametrize(("name", "shut"), [("house", 4), ("house_open", 3)])
def test_rooms_behind_closed_doors_are_shut_in_an_open_doorway_is_not(tmp_path, name, shut):
    _, storey = storey_of(tmp_path, name)
    plan = plan_storey(storey, SurveyParams(spacing=2.0, headings=1))
    assert len(plan.shut_in) == shut  # living room, kitchen, staircase (and the bedroom, door shut)
    assert len(bedroom(plan.shut_in)) == (1 if name == "house" else 0)
    for room in bedroom(plan.shut_in):
        assert 12.0 <= room.area_m2 <= 30.0  # the 5 x 6 m room less the start clearance
    assert plan.shut_in_cells is not None and not (plan.shut_in_cells & plan.circulation.label).any()


def test_survey_json_lists_the_shut_in_rooms(tmp_path):
    site_dir, _ = storey_of(tmp_path, "house")
    out = tmp_path / "sv"
    args = [
        "survey",
        str(site_dir),
        "--out",
        str(out),
        "--spacing",
        "1",
        "--headings",
        "1",
        "--landmarks",
        "0",
    ]
    result = CliRunner().invoke(app, [*args, "--workers", "1"])
    assert result.exit_code == 0, result.output
    doc = json.loads((out / "survey.json").read_text())
    jsonschema.validate(doc, json.loads((SCHEMAS / "survey.schema.json").read_text()))
    (storey,) = doc["storeys"]
    assert len(storey["shut_in_rooms"]) == 4
    assert storey["shut_in_area_m2"] == pytest.approx(
        sum(r["area_m2"] for r in storey["shut_in_rooms"]), abs=0.2
    )
    assert (out / "survey_Level_1.png").stat().st_size > 0
