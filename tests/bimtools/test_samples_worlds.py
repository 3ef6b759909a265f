"""The test worlds of issue 31 (bimtools.samples.worlds): halls whose gates stand open, a house, and
as-built variants of the samples, written by the sample IFC writer and read back by bim-extract."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bimtools.extract.pipeline import extract_site
from bimtools.samples.layouts import check_plan
from bimtools.samples.plans import plan
from bimtools.samples.worlds import AS_BUILT_CHANGES, WORLDS, sample_as_built, world, write_plan
from bimtools.site.records import FREE


@pytest.mark.parametrize("name", sorted(WORLDS))
def test_the_test_worlds_are_valid_plans(name):
    assert check_plan(world(name)) == []


def test_an_open_halls_free_space_is_bounded_by_its_floor_slab(tmp_path):
    """Both end gates stand open: without the slab the hall's floor is outside the footprint (no free
    cell at all); with it, the free space is the hall's floor and no more."""
    hall = world("open_hall")
    bare = dataclasses.replace(hall, name="open_hall_without_slab", with_slab=False)
    for floor, low, high in ((hall, 0.9 * 48 * 16, 48 * 16), (bare, 0.0, 0.0)):
        (storey,) = extract_site(write_plan(floor, tmp_path)).storeys
        grid = storey.grid
        free_m2 = float((np.asarray(grid.cells) == FREE).sum()) * grid.resolution**2
        assert low <= free_m2 <= high, floor.name
        assert len(storey.features) == 9  # the doors; the gates are openings no door fills


@pytest.mark.parametrize("name", sorted(AS_BUILT_CHANGES))
def test_as_built_variants_change_the_doors_they_name(tmp_path, name):
    built = sample_as_built(name)
    changes = AS_BUILT_CHANGES[name]
    design = plan(name)
    gone = set(changes["removed"]) | set(changes["walled"])  # type: ignore[arg-type]
    assert {d.tag for d in built.doors} == {d.tag for d in design.doors} - gone
    assert {d.tag for d in built.openings} >= set(changes["removed"])  # type: ignore[arg-type]
    site = extract_site(write_plan(built, tmp_path))
    assert sum(len(s.features) for s in site.storeys) < sum(1 for _ in design.doors) + len(
        design.lifts
    ) + len(design.stairs)
