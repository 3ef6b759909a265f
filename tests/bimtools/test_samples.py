"""The deterministic sample models (bimtools.samples): paper facts, IFC validity, ground truth."""

from __future__ import annotations

import json
import math
import re
from functools import cache
from pathlib import Path

import ifcopenshell
import ifcopenshell.guid
import ifcopenshell.util.element
import ifcopenshell.util.placement
import ifcopenshell.validate
import numpy as np
import pytest
from shapely.geometry import Point, Polygon
from shapely.ops import unary_union

from bimtools import samples
from bimtools.samples import layouts, plans
from bimtools.samples.__main__ import main
from tests.helpers import SAMPLES

LIFT_RE = re.compile(r"lift|elevator|aufzug", re.IGNORECASE)


# Paper §4.1: doors (by truth category), lifts and staircases per environment.
EXPECTED = {
    "ntu_hallway": {"Door": 38, "Lift": 5, "Stairs": 0, "spaces": False},
    "block_a": {"Door": 13, "Lift": 3, "Stairs": 2, "spaces": True},
    "block_b": {"Door": 13, "Lift": 3, "Stairs": 2, "spaces": True},
}


CORRIDOR_M = {"ntu_hallway": (185.0, 195.0), "block_a": (60.8, 61.8), "block_b": (62.3, 63.3)}


@cache
def built(name: str) -> tuple[ifcopenshell.file, dict]:
    return samples.build(name)


def _matrix(product: ifcopenshell.entity_instance) -> np.ndarray:
    return ifcopenshell.util.placement.get_local_placement(product.ObjectPlacement)


def _wall_footprint(wall: ifcopenshell.entity_instance) -> Polygon:
    """The wall's extruded profile (IfcIndexedPolyCurve, as written) in storey XY coordinates."""
    body = next(r for r in wall.Representation.Representations if r.RepresentationIdentifier == "Body")
    solid = body.Items[0]
    pts = np.array(solid.SweptArea.OuterCurve.Points.CoordList, dtype=float)
    pts[:, 1] += solid.Position.Location.Coordinates[1]
    m = _matrix(wall)
    return Polygon([tuple((m @ np.array([x, y, 0.0, 1.0]))[:2]) for x, y in pts])


def test_models_are_the_three_paper_environments() -> None:
    assert samples.MODELS == ("ntu_hallway", "block_a", "block_b")


@pytest.mark.parametrize("name", samples.MODELS)
def test_plans_are_consistent(name: str) -> None:
    assert layouts.check_plan(plans.plan(name)) == []


@pytest.mark.parametrize("name", samples.MODELS)
def test_generation_is_deterministic(name: str) -> None:
    model, truth = built(name)
    again, truth_again = samples.build(name)
    assert samples.ifc_text(again) == samples.ifc_text(model)
    assert samples.truth_text(truth_again) == samples.truth_text(truth)


@pytest.mark.parametrize("name", samples.MODELS)
def test_committed_files_equal_a_fresh_generation(name: str) -> None:
    model, truth = built(name)
    ifc_path, truth_path = SAMPLES / f"{name}.ifc", SAMPLES / f"{name}.truth.json"
    hint = "regenerate with: python -m bimtools.samples --out sample_models"
    assert ifc_path.read_text(encoding="utf-8") == samples.ifc_text(model), hint
    assert truth_path.read_text(encoding="utf-8") == samples.truth_text(truth), hint


@pytest.mark.parametrize("name", samples.MODELS)
def test_models_validate(name: str) -> None:
    model, _ = built(name)
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(model, logger)
    assert logger.statements == []


def test_model_passes_express_rules() -> None:
    model, _ = built("block_b")  # ~3 s per model: one is enough, they share all the code
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(model, logger, express_rules=True)
    assert logger.statements == []


@pytest.mark.parametrize("name", samples.MODELS)
def test_spatial_structure(name: str) -> None:
    model, truth = built(name)
    assert model.schema == "IFC4"
    (storey,) = model.by_type("IfcBuildingStorey")
    assert (storey.Name, storey.Elevation) == ("Level 1", 0.0)
    assert truth["storeys"] == [{"name": "Level 1", "elevation": 0.0, "height": 3.0}]
    qto = ifcopenshell.util.element.get_psets(storey)["Qto_BuildingStoreyBaseQuantities"]
    assert qto["GrossHeight"] == pytest.approx(3.0)
    length_unit = next(u for u in model.by_type("IfcSIUnit") if u.UnitType == "LENGTHUNIT")
    assert (length_unit.Name, length_unit.Prefix) == ("METRE", None)
    assert ifcopenshell.util.element.get_aggregate(storey).is_a("IfcBuilding")
    contained = set(storey.ContainsElements[0].RelatedElements)
    for cls in ("IfcWall", "IfcDoor", "IfcTransportElement", "IfcStair"):
        assert set(model.by_type(cls)) <= contained, cls
    guids = [e.GlobalId for e in model.by_type("IfcRoot")]
    assert len(set(guids)) == len(guids)
    assert all(ifcopenshell.guid.compress(ifcopenshell.guid.expand(g)) == g for g in guids)


@pytest.mark.parametrize("name", samples.MODELS)
def test_element_counts_match_the_paper(name: str) -> None:
    model, truth = built(name)
    want = EXPECTED[name]
    categories = [f["Category"] for f in truth["features"]]
    for category in ("Door", "Lift", "Stairs"):
        assert categories.count(category) == want[category], category
    assert len(model.by_type("IfcDoor")) == len(truth["features"])
    lifts = model.by_type("IfcTransportElement")
    assert len(lifts) == want["Lift"] and all(t.PredefinedType == "ELEVATOR" for t in lifts)
    stairs = model.by_type("IfcStair")
    assert len(stairs) == want["Stairs"]
    for stair in stairs:
        (flight,) = ifcopenshell.util.element.get_parts(stair)
        assert flight.is_a("IfcStairFlight")
    assert bool(model.by_type("IfcSpace")) == want["spaces"]
    if name.startswith("block"):
        gates = [f for f in truth["features"] if f["Name"].endswith("main gate")]
        assert len(gates) == 13


@pytest.mark.parametrize("name", samples.MODELS)
def test_corridor_length(name: str) -> None:
    _, truth = built(name)
    lo, hi = CORRIDOR_M[name]
    assert lo <= truth["corridor_length_m"] <= hi


@pytest.mark.parametrize("name", samples.MODELS)
def test_each_door_fills_an_opening_that_voids_a_wall(name: str) -> None:
    model, _ = built(name)
    for door in model.by_type("IfcDoor"):
        (fills,) = door.FillsVoids
        opening = fills.RelatingOpeningElement
        assert opening.is_a("IfcOpeningElement")
        (voids,) = opening.VoidsElements
        wall = voids.RelatingBuildingElement
        assert wall.is_a("IfcWall")
        door_origin = _matrix(door)[:2, 3]
        assert _wall_footprint(wall).buffer(1e-6).contains(Point(*door_origin))


@pytest.mark.parametrize("name", samples.MODELS)
def test_truth_matches_door_placement_and_size(name: str) -> None:
    """Truth X,Y = door origin + t/2 * local Y; normal = local Y; size = OverallWidth/Height."""
    model, truth = built(name)
    doors = {d.GlobalId: d for d in model.by_type("IfcDoor")}
    for f in truth["features"]:
        door = doors[f["ID"]]
        m = _matrix(door)
        origin, y_axis = m[:3, 3], m[:3, 1]
        face = origin + y_axis * layouts.WALL_THICKNESS / 2
        assert (f["X"], f["Y"]) == pytest.approx((face[0], face[1]), abs=1e-9)
        assert (f["Norm_X"], f["Norm_Y"]) == pytest.approx((y_axis[0], y_axis[1]), abs=1e-9)
        assert math.hypot(f["Norm_X"], f["Norm_Y"]) == pytest.approx(1.0)
        assert (f["Width"], f["Height"]) == (door.OverallWidth, door.OverallHeight)
        assert (f["IfcClass"], f["Storey"], f["Name"]) == ("IfcDoor", "Level 1", door.Name)
        body = door.Representation.Representations[0].Items[0]
        assert (body.SweptArea.XDim, body.SweptArea.YDim, body.Depth) == pytest.approx(
            (door.OverallWidth, layouts.WALL_THICKNESS, door.OverallHeight)
        )


@pytest.mark.parametrize("name", samples.MODELS)
def test_lift_and_stair_features(name: str) -> None:
    model, truth = built(name)
    cars = {t.Name: _matrix(t)[:2, 3] for t in model.by_type("IfcTransportElement")}
    flights = [_matrix(s)[:2, 3] for s in model.by_type("IfcStair")]
    for f in truth["features"]:
        at = np.array([f["X"], f["Y"]])
        if f["Category"] == "Lift":
            assert LIFT_RE.search(f["Name"]), f["Name"]
            car = cars[f["Name"].removesuffix(" landing door")]
            assert np.dot(car - at, [f["Norm_X"], f["Norm_Y"]]) < 0  # the car is behind the door
            assert np.linalg.norm(car - at) < 2.0
        else:
            assert not LIFT_RE.search(f["Name"]), f["Name"]
        if f["Category"] == "Stairs":
            assert f["Name"] == "Door"
            assert min(np.linalg.norm(p - at) for p in flights) < 3.0


@pytest.mark.parametrize("name", ["block_a", "block_b"])
def test_spaces_name_the_rooms(name: str) -> None:
    model, _ = built(name)
    spaces = model.by_type("IfcSpace")
    names = {s.Name for s in spaces}
    assert {"Lift Lobby", "Lift 1", "Lift 2", "Lift 3", "Stair 1", "Stair 2", "Unit 01", "Unit 13"} <= names
    assert any(n.startswith("Corridor") for n in names)
    for space in spaces:
        assert ifcopenshell.util.element.get_aggregate(space).is_a("IfcBuildingStorey")
        assert space.Representation is not None


@pytest.mark.parametrize("name", samples.MODELS)
def test_free_and_wall_points(name: str) -> None:
    model, truth = built(name)
    walls = unary_union([_wall_footprint(w) for w in model.by_type("IfcWall")])
    assert len(truth["free_points"]) >= 10 and len(truth["wall_points"]) >= 10
    for x, y in truth["free_points"]:
        assert walls.distance(Point(x, y)) >= 0.5 - 1e-9, (x, y)
    openings = [_matrix(d)[:2, 3] for d in model.by_type("IfcDoor")]
    for x, y in truth["wall_points"]:
        assert walls.contains(Point(x, y)), (x, y)
        assert min(np.linalg.norm(o - (x, y)) for o in openings) > 0.5, (x, y)


def test_cli_writes_model_and_truth(tmp_path: Path) -> None:
    assert main(["--out", str(tmp_path), "--name", "block_a"]) == 0
    model, truth = built("block_a")
    assert (tmp_path / "block_a.ifc").read_text(encoding="utf-8") == samples.ifc_text(model)
    assert json.loads((tmp_path / "block_a.truth.json").read_text(encoding="utf-8")) == truth
    assert sorted(p.name for p in tmp_path.iterdir()) == ["block_a.ifc", "block_a.truth.json"]
