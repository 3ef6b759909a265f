"""bim-extract on real IFC models from other authors (../shared/ifc); skipped when absent."""

from __future__ import annotations

import functools
from collections import Counter
from pathlib import Path

import ifcopenshell
import ifcopenshell.geom
import numpy as np
import pytest

from bimkit.atomic import RECORD
from bimtools.extract.pipeline import ExtractedSite
from tests.helpers import SHARED_IFC, extracted_all_storeys, shared_ifc_files

pytestmark = pytest.mark.skipif(not SHARED_IFC.is_dir(), reason=f"{SHARED_IFC} is absent")


FILES = [p.name for p in shared_ifc_files()]


WITH_LIFTS = {
    "Office_A_20110811.ifc",
    "FM_ARC_DigitalHub.ifc",
    "LiNear_Office_Building_Architectural_IFC_export.ifc",
}


def extracted(name: str) -> ExtractedSite:
    return extracted_all_storeys(SHARED_IFC / name)


@functools.cache
def door_bbox_centres(name: str) -> dict[str, np.ndarray]:
    """Bounding-box centres (XY) of every IfcDoor's own geometry, computed independently."""
    model = ifcopenshell.open(str(SHARED_IFC / name))
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    centres = {}
    for door in model.by_type("IfcDoor"):
        if door.Representation is None:
            continue
        try:
            shape = ifcopenshell.geom.create_shape(settings, door)
        except RuntimeError:
            continue
        verts = np.asarray(shape.geometry.verts).reshape(-1, 3)
        if len(verts):
            centres[door.GlobalId] = (verts[:, :2].min(axis=0) + verts[:, :2].max(axis=0)) / 2
    return centres


@pytest.mark.parametrize("name", FILES)
def test_every_door_becomes_a_feature_near_its_geometry(name):
    site = extracted(name)
    rows = {f.id: f for f in site.features}
    centres = door_bbox_centres(name)
    assert centres, "model has doors with geometry"
    missing = sorted(set(centres) - set(rows))
    assert not missing, f"{len(missing)} IfcDoor(s) without a feature row: {missing[:5]}"
    for guid, centre in centres.items():
        f = rows[guid]
        assert f.category in ("Door", "Lift", "Stairs")
        distance = float(np.hypot(f.x - centre[0], f.y - centre[1]))
        assert distance <= 0.3, f"{guid} ({f.category}) is {distance:.2f} m from its bbox centre"
        assert abs(np.hypot(f.norm_x, f.norm_y) - 1) < 1e-6


@pytest.mark.parametrize("name", FILES)
def test_lifts_and_stairs_are_found_where_the_model_has_them(name):
    site = extracted(name)
    counts = Counter(f.category for f in site.features)
    model = ifcopenshell.open(str(SHARED_IFC / name))
    if name in WITH_LIFTS:
        assert counts["Lift"] >= 1
    if model.by_type("IfcStair") or model.by_type("IfcStairFlight"):
        assert counts["Stairs"] >= 1
    ids = [(f.id, f.storey) for f in site.features]
    assert len(ids) == len(set(ids)), "one row per element and storey"


def test_office_a_elevator_is_one_lift_per_storey():
    lifts = [f for f in extracted("Office_A_20110811.ifc").features if f.category == "Lift"]
    per_storey = Counter(f.storey for f in lifts)
    assert per_storey == {"Level 1": 1, "Level 2": 1}
    assert {f.ifc_class for f in lifts} == {"IfcFlowTerminal"}


def test_storeys_without_elevation_are_ordered(tmp_path):
    site = extracted("ExampleHOM.ifc")
    elevations = [s.storey.elevation for s in site.storeys]
    assert elevations == sorted(elevations) and len(set(elevations)) == len(elevations)


def test_wall_normals_point_into_free_space():
    import shapely

    for s in extracted("AC20-Institute-Var-2.ifc").storeys:
        solid = s.plan.solid
        for w in s.plan.walls:
            if w.length < 0.2:
                continue
            # 5 mm either side: curtain-wall panels and door leaves can be 1-3 cm thick,
            # so a larger offset would step right through the element.
            mx, my = (w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2
            outside = shapely.Point(mx + 0.005 * w.normal[0], my + 0.005 * w.normal[1])
            inside = shapely.Point(mx - 0.005 * w.normal[0], my - 0.005 * w.normal[1])
            assert not solid.contains(outside) and solid.buffer(1e-6).contains(inside)


def test_cli_writes_all_files(tmp_path):
    from typer.testing import CliRunner

    from bimtools.cli import app

    result = CliRunner().invoke(
        app, [str(SHARED_IFC / "AC20-FZK-Haus.ifc"), "-o", str(tmp_path / "out"), "--json"]
    )
    assert result.exit_code == 0, result.output
    import json

    manifest = json.loads(result.stdout)
    names = {p.name for p in Path(tmp_path / "out").iterdir()}
    assert set(manifest["files"]) == names - {RECORD}  # and the record of what the tool wrote
    assert RECORD in names
    assert manifest["schema"] == "IFC4" and manifest["application"] == "ARCHICAD-64"
    assert manifest["storeys"][0]["name"] == "Erdgeschoss"
