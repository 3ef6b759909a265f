"""bimtools.ifc.storeys: storey elevations, unique names and slugs, containment, lookup by height."""

from __future__ import annotations

import ifcopenshell
import ifcopenshell.api.aggregate
import ifcopenshell.api.root
import ifcopenshell.api.spatial
import numpy as np
import pytest

from bimtools.ifc.storeys import Storey, container_storey, list_storeys, storey_at_elevation, storey_slug


def _storey(model: ifcopenshell.file, name: str | None, elevation: float | None, z: float | None = None):
    storey = ifcopenshell.api.root.create_entity(model, ifc_class="IfcBuildingStorey", name=name)
    storey.Elevation = elevation
    if z is not None:
        origin = model.createIfcAxis2Placement3D(model.createIfcCartesianPoint((0.0, 0.0, z)), None, None)
        storey.ObjectPlacement = model.createIfcLocalPlacement(None, origin)
    return storey


@pytest.mark.parametrize(
    ("name", "slug"),
    [
        ("Level 1", "Level_1"),
        ("  B1 / Car park ", "B1_Car_park"),
        ("L-2.5", "L-2_5"),
        ("Уровень 1", "Уровень_1"),
    ],
)
def test_storey_slug(name: str, slug: str) -> None:
    assert storey_slug(name) == slug


def test_list_storeys_sorts_scales_and_deduplicates() -> None:
    model = ifcopenshell.file(schema="IFC4")
    _storey(model, "Level 2", 3000.0)
    _storey(model, "Level 1", 0.0)
    _storey(model, "Level 2", 6000.0)
    _storey(model, "Level-2", 9000.0)
    storeys = list_storeys(model, 0.001)
    assert [s.elevation for s in storeys] == pytest.approx([0.0, 3.0, 6.0, 9.0])
    assert [s.name for s in storeys] == ["Level 1", "Level 2", "Level 2 (2)", "Level-2"]
    assert [s.slug for s in storeys] == ["Level_1", "Level_2", "Level_2_2", "Level-2"]


def test_names_that_differ_only_in_punctuation_get_distinct_slugs() -> None:
    model = ifcopenshell.file(schema="IFC4")
    _storey(model, "Level 2", 0.0)
    _storey(model, "Level/2", 3.0)
    assert [s.slug for s in list_storeys(model, 1.0)] == ["Level_2", "Level_2_2"]


def test_slugs_stay_unique_when_a_renamed_slug_collides() -> None:
    model = ifcopenshell.file(schema="IFC4")
    _storey(model, "Level 2", 0.0)
    _storey(model, "Level 2", 3.0)  # renamed "Level 2 (2)": slug Level_2_2
    _storey(model, "Level/2", 6.0)  # slug Level_2, taken: renamed Level_2_2, taken too
    slugs = [s.slug for s in list_storeys(model, 1.0)]
    assert len(set(slugs)) == len(slugs), slugs


def test_elevation_from_placement_when_missing_or_zero() -> None:
    model = ifcopenshell.file(schema="IFC4")
    _storey(model, "placed", None, z=4.5)
    _storey(model, "zero but placed", 0.0, z=7.0)
    _storey(model, "nothing", None)
    storeys = {s.name: s.elevation for s in list_storeys(model, 1.0)}
    assert storeys["placed"] == pytest.approx(4.5)
    assert storeys["zero but placed"] == pytest.approx(7.0)
    assert storeys["nothing"] == pytest.approx(6.0)  # third in file order, 3 m apart


def test_a_rounding_residue_is_elevation_zero() -> None:
    model = ifcopenshell.file(schema="IFC4")
    _storey(model, "level 0", -2e-11)  # as a Revit 2013 export writes it, in mm
    (storey,) = list_storeys(model, 0.001)
    assert f"{storey.elevation:.2f}" == "0.00"  # not -0.00 in tables, features.csv or site.json


def test_unnamed_storeys_get_numbered_names() -> None:
    model = ifcopenshell.file(schema="IFC4")
    _storey(model, None, 0.0)
    _storey(model, None, 3.0)
    assert [s.name for s in list_storeys(model, 1.0)] == ["Storey 1", "Storey 2"]


def test_container_storey_through_spaces_and_aggregates() -> None:
    model = ifcopenshell.file(schema="IFC4")
    storey = _storey(model, "L1", 0.0)
    space = ifcopenshell.api.root.create_entity(model, ifc_class="IfcSpace", name="101")
    ifcopenshell.api.aggregate.assign_object(model, products=[space], relating_object=storey)
    door = ifcopenshell.api.root.create_entity(model, ifc_class="IfcDoor")
    ifcopenshell.api.spatial.assign_container(model, products=[door], relating_structure=space)
    stair = ifcopenshell.api.root.create_entity(model, ifc_class="IfcStair")
    ifcopenshell.api.spatial.assign_container(model, products=[stair], relating_structure=storey)
    flight = ifcopenshell.api.root.create_entity(model, ifc_class="IfcStairFlight")
    ifcopenshell.api.aggregate.assign_object(model, products=[flight], relating_object=stair)
    loose = ifcopenshell.api.root.create_entity(model, ifc_class="IfcWall")
    assert container_storey(door) == storey
    assert container_storey(stair) == storey
    assert container_storey(flight) == storey
    assert container_storey(space) == storey
    assert container_storey(loose) is None


def test_storey_at_elevation() -> None:
    storeys = [Storey(f"L{i}", 3.0 * i, None) for i in range(3)]  # type: ignore[arg-type]
    assert storey_at_elevation(storeys, 0.0).name == "L0"
    assert storey_at_elevation(storeys, 2.8).name == "L1"  # within the 0.3 m tolerance
    assert storey_at_elevation(storeys, 2.6).name == "L0"
    assert storey_at_elevation(storeys, 100.0).name == "L2"
    assert storey_at_elevation(storeys, -5.0).name == "L0"  # below everything: the lowest
    assert np.isfinite(storey_at_elevation(storeys, 4.0).elevation)
