"""The site model's self-similarity (initcli.config.building.self_similar, twin_reason) on IFC models
written by
the sample writer and extracted as bim-extract does."""

from __future__ import annotations

from pathlib import Path

import pytest

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.samples.worlds import as_built_plan, world, write_plan
from bimtools.site.load import Site, load_site
from initcli.config.building import SELF_SIMILAR, self_similar, twin_reason


def extracted(tmp_path: Path, plan) -> Site:
    ifc = write_plan(plan, tmp_path)
    write_site(tmp_path / plan.name, extract_site(ifc), preview=False)
    return load_site(tmp_path / plan.name)


def test_semi_detached_homes_are_the_same_turned_half_round(tmp_path):
    site = extracted(tmp_path, world("semi_detached"))
    (storey,) = site.storeys
    turn = self_similar(site.storeys[storey])
    assert turn is not None and turn.degrees == pytest.approx(180.0)
    assert turn.centre == pytest.approx((8.0, 5.0), abs=0.01)  # the middle of the party wall
    reason = twin_reason(site, storey)
    assert reason is not None and reason.startswith(f"{SELF_SIMILAR}: ")
    assert "turned 180 deg about (8.00, 5.00)" in reason
    assert twin_reason(site, None) == reason  # every storey with a map: the one


@pytest.mark.parametrize(
    "change",
    [
        {"shifted": {"D001": 0.6}},  # one door 0.6 m along its wall in the model
        {"walled": ("D006",)},  # one door walled up in the model
    ],
)
def test_one_door_not_alike_keeps_the_storey_apart(tmp_path, change):
    site = extracted(tmp_path, as_built_plan(world("semi_detached"), **change))
    (storey,) = site.storeys
    assert self_similar(site.storeys[storey]) is None and twin_reason(site, storey) is None


def test_the_house_is_not_self_similar(tmp_path):
    site = extracted(tmp_path, world("house"))
    assert all(self_similar(s) is None for s in site.storeys.values())
