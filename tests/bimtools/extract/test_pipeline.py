"""bim-extract on the generated sample models, against the generator's ground truth."""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from bimkit.atomic import RECORD
from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.site.load import load_site
from bimtools.site.records import FREE, OCCUPIED
from tests.helpers import SAMPLES, SCHEMAS

MODELS = ["ntu_hallway", "block_a", "block_b"]


def truth(name: str) -> dict:
    return json.loads((SAMPLES / f"{name}.truth.json").read_text())


@functools.cache
def site_dir(name: str, root: str) -> Path:
    out = Path(root) / f"{name}_site"
    write_site(out, extract_site(SAMPLES / f"{name}.ifc"))
    return out


@pytest.fixture(scope="module")
def out_root(tmp_path_factory) -> str:
    return str(tmp_path_factory.mktemp("samples"))


@pytest.mark.parametrize("name", MODELS)
def test_features_match_ground_truth(name, out_root):
    expected = {f["ID"]: f for f in truth(name)["features"]}
    site = load_site(site_dir(name, out_root))
    (storey,) = site.storeys.values()
    got = {f.id: f for f in storey.features}
    assert sorted(got) == sorted(expected), "exactly the generator's features"
    for guid, want in expected.items():
        f = got[guid]
        assert f.category == want["Category"], guid
        assert math.hypot(f.x - want["X"], f.y - want["Y"]) <= 0.01, (guid, f, want)
        angle = math.degrees(
            abs(
                math.atan2(
                    f.norm_x * want["Norm_Y"] - f.norm_y * want["Norm_X"],
                    f.norm_x * want["Norm_X"] + f.norm_y * want["Norm_Y"],
                )
            )
        )
        assert angle <= 2.0, (guid, angle)
        assert f.width == pytest.approx(want["Width"], abs=0.01)
        assert f.height == pytest.approx(want["Height"], abs=0.01)


@pytest.mark.parametrize("name", MODELS)
def test_map_round_trip_free_corridors_and_occupied_walls(name, out_root):
    site = load_site(site_dir(name, out_root))
    (storey,) = site.storeys.values()
    grid = storey.grid
    assert grid is not None
    doc = truth(name)
    for x, y in doc["free_points"]:
        assert grid.value_at(x, y) == FREE, (x, y)
    reach = doc["wall_thickness_m"] / 2 + grid.resolution
    offsets = np.arange(-reach, reach + 1e-9, grid.resolution / 4)
    for x, y in doc["wall_points"]:
        assert grid.value_at(x, y) != FREE, (x, y)
        # Walls are drawn as outlines: crossing the wall meets an occupied cell on its face.
        across = [grid.value_at(x + d, y) for d in offsets] + [grid.value_at(x, y + d) for d in offsets]
        assert OCCUPIED in across, (x, y)


@pytest.mark.parametrize("name", MODELS)
def test_wall_normals_point_into_free_space(name, out_root):
    site = load_site(site_dir(name, out_root))
    (storey,) = site.storeys.values()
    solid = shapely.union_all([shapely.Polygon(o.exterior, o.holes) for o in storey.obstacles])
    assert storey.walls
    for w in storey.walls:
        mx, my = (w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2
        assert math.hypot(*w.normal) == pytest.approx(1.0, abs=1e-5)
        assert not solid.contains(shapely.Point(mx + 0.02 * w.normal[0], my + 0.02 * w.normal[1]))
        assert solid.buffer(1e-3).contains(shapely.Point(mx - 0.02 * w.normal[0], my - 0.02 * w.normal[1]))


def test_outside_the_building_is_unknown(out_root):
    site = load_site(site_dir("block_a", out_root))
    grid = site.storeys["Level 1"].grid
    assert grid.value_at(grid.origin[0] + 0.1, grid.origin[1] + 0.1) == 205
    # No free cell is outside the obstacle-bounded outline: the border rows are unknown.
    assert not (grid.cells[0] == FREE).any() and not (grid.cells[:, -1] == FREE).any()


def test_manifest_describes_the_run(out_root):
    manifest = json.loads((site_dir("ntu_hallway", out_root) / "site.json").read_text())
    assert manifest["storeys"] == [
        {
            "name": "Level 1",
            "elevation": 0.0,
            "counts": {"Lift": 5, "Door": 38},
            "map_yaml": "map_Level_1.yaml",
            "preview": "preview_Level_1.png",
        }
    ]
    assert manifest["schema"] == "IFC4" and manifest["length_unit"] == "METRE"
    assert manifest["section_height"] == 1.0
    assert len(manifest["source"]["sha256"]) == 64
    record = {RECORD}  # the list of what bim-extract wrote there (bimkit.atomic)
    files = {p.name for p in site_dir("ntu_hallway", out_root).iterdir()} - record
    assert files == set(manifest["files"])


def test_outputs_validate_against_published_schemas(out_root):
    import jsonschema
    import yaml

    schemas = SCHEMAS
    root = site_dir("block_b", out_root)
    jsonschema.validate(
        json.loads((root / "site.json").read_text()), json.loads((schemas / "site.schema.json").read_text())
    )
    jsonschema.validate(
        json.loads((root / "walls.geojson").read_text()),
        json.loads((schemas / "walls.schema.json").read_text()),
    )
    jsonschema.validate(
        yaml.safe_load((root / "map_Level_1.yaml").read_text()),
        json.loads((schemas / "map.schema.json").read_text()),
    )
    import csv

    feature_schema = json.loads((schemas / "features.schema.json").read_text())
    with open(root / "features.csv") as handle:
        for row in csv.DictReader(handle):
            typed = {
                k: (float(v) if k in ("X", "Y", "Norm_X", "Norm_Y", "Width", "Height", "Elevation") else v)
                for k, v in row.items()
            }
            jsonschema.validate(typed, feature_schema)
    import yaml as _yaml

    from bimtools.ifc.categories import DEFAULT_CATEGORIES

    jsonschema.validate(
        _yaml.safe_load(DEFAULT_CATEGORIES.read_text()),
        json.loads((schemas / "categories.schema.json").read_text()),
    )


def test_user_defined_category_by_regex(tmp_path):
    cats = tmp_path / "cats.yaml"
    cats.write_text(
        "categories:\n"
        "  - name: Gate\n    kind: door\n    doors: [{classes: [IfcDoor], text: 'main gate'}]\n"
        "  - name: Door\n    kind: door\n    doors: [{classes: [IfcDoor]}]\n"
    )
    from bimtools.ifc.categories import load_categories

    site = extract_site(SAMPLES / "block_a.ifc", load_categories(cats))
    counts: dict[str, int] = {}
    for f in site.features:
        counts[f.category] = counts.get(f.category, 0) + 1
    assert counts == {"Gate": 13, "Door": 5}


def test_section_height_and_resolution_are_applied(tmp_path):
    site = extract_site(SAMPLES / "block_a.ifc", section_height=1.5, resolution=0.1)
    (result,) = site.storeys
    assert result.plan.cut_height == pytest.approx(1.5)
    assert result.grid.resolution == 0.1
    assert np.isin(result.grid.cells, [0, 205, 254]).all()
