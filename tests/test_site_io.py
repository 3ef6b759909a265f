"""Round trips of every site-model file format, and their bad-input errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.errors import InputError
from bimtools.site.features_csv import format_features, read_features, write_features
from bimtools.site.load import load_site
from bimtools.site.manifest import SiteManifest, format_manifest, read_manifest
from bimtools.site.occupancy_map import FREE, OCCUPIED, UNKNOWN, OccupancyGrid, read_map, write_map
from bimtools.site.records import TABLE1_COLUMNS, Feature, Obstacle, StoreyInfo, WallSegment
from bimtools.site.walls_geojson import read_walls, write_walls

FEATURES = [
    Feature("62938", "Door", -6.38, -4.14, 1.0, 0.0, 1.05, 2.30, "L1", 0.0, "IfcDoor", "Door, 1"),
    Feature("96688", "Lift", -5.07, 0.0, 0.0, -1.0, 1.10, 2.12, "L1", 0.0, "IfcTransportElement", "Lift A"),
    Feature("94617", "Stairs", -3.39, 58.41, -1.0, 0.0, 1.19, 1.86, "L2", 3.2, "IfcStair", 'Stair "B"'),
]


def test_features_csv_round_trip(tmp_path):
    path = tmp_path / "features.csv"
    write_features(path, FEATURES)
    assert path.read_text().splitlines()[0].split(",")[:8] == list(TABLE1_COLUMNS)
    assert read_features(path) == FEATURES


def test_hand_written_table1_is_enough(tmp_path):
    path = tmp_path / "table1.csv"
    path.write_text("ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n62938,Door,-6.38,-4.14,2,0,1.05,2.30\n")
    (feature,) = read_features(path)
    assert feature.id == "62938" and feature.storey == "" and feature.norm_x == 1.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("ID,Category,X,Y\n1,Door,0,0\n", "missing column(s) Norm_X"),
        (
            "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n1,Door,abc,0,1,0,1,2\n",
            ":2: column X: expected a number",
        ),
        (
            "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n1,Door,0,0,1,0,1,2\n2,Door,0,0,0,0,1,2\n",
            ":3: Norm_X, Norm_Y is the zero",
        ),
        ("ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n,Door,0,0,1,0,1,2\n", ":2: column ID is empty"),
    ],
)
def test_features_csv_errors_name_the_line(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        read_features(path)


def test_walls_geojson_round_trip_and_storey_filter(tmp_path):
    walls = [
        WallSegment("L1", "w1", "IfcWall", 0, 0, 4, 0, (0.0, 1.0)),
        WallSegment("L2", "w2", "IfcWall", 1, 1, 1, 5, (-1.0, 0.0)),
    ]
    obstacles = [Obstacle("L1", "w1", "IfcWall", ((0, -0.2), (4, -0.2), (4, 0), (0, 0), (0, -0.2)))]
    path = tmp_path / "walls.geojson"
    write_walls(path, walls, obstacles)
    got_walls, got_obstacles = read_walls(path)
    assert got_walls == walls
    assert got_obstacles[0].exterior == tuple((float(x), float(y)) for x, y in obstacles[0].exterior)
    only_l2, none = read_walls(path, storey="L2")
    assert [w.element for w in only_l2] == ["w2"] and none == []


def test_map_round_trip_and_world_lookup(tmp_path):
    cells = np.full((40, 60), UNKNOWN, dtype=np.uint8)
    cells[10:30, 10:50] = FREE
    cells[10, 10:50] = OCCUPIED
    grid = OccupancyGrid(cells, 0.05, (-1.5, 2.0, 0.0))
    write_map(tmp_path / "map_L1.yaml", grid)
    back = read_map(tmp_path / "map_L1.yaml")
    assert np.array_equal(back.cells, cells) and back.origin == (-1.5, 2.0, 0.0) and back.resolution == 0.05
    # row 0 is the top: the lower-left pixel is at the origin.
    assert back.value_at(-1.5 + 0.025, 2.0 + 0.025) == UNKNOWN
    x, y = back.cell_centre(20, 30)
    assert back.value_at(float(x), float(y)) == FREE
    x, y = back.cell_centre(10, 30)
    assert back.value_at(float(x), float(y)) == OCCUPIED
    state = back.occupancy()
    assert state[10, 30] == 1 and state[20, 30] == 0 and state[0, 0] == -1


def test_truncated_pgm_is_reported(tmp_path):
    grid = OccupancyGrid(np.full((10, 10), FREE, dtype=np.uint8), 0.1, (0.0, 0.0, 0.0))
    write_map(tmp_path / "m.yaml", grid)
    data = (tmp_path / "m.pgm").read_bytes()
    (tmp_path / "m.pgm").write_bytes(data[:-5])
    with pytest.raises(InputError, match="truncated"):
        read_map(tmp_path / "m.yaml")


def test_manifest_round_trip(tmp_path):
    manifest = SiteManifest(
        "a.ifc",
        "00" * 32,
        "IFC4",
        "Tool",
        "METRE",
        1.0,
        1.0,
        0.05,
        [StoreyInfo("L1", 0.0, {"Door": 3}, "map_L1.yaml", "preview_L1.png")],
        ["features.csv"],
        "0.1.0",
    )
    (tmp_path / "site.json").write_text(format_manifest(manifest))
    assert read_manifest(tmp_path / "site.json") == manifest


def test_load_site_from_folder_and_from_csv(tmp_path):
    write_features(tmp_path / "features.csv", FEATURES)
    site = load_site(tmp_path)
    assert sorted(site.storeys) == ["L1", "L2"]
    assert [f.id for f in site.storey("L1").features] == ["62938", "96688"]
    with pytest.raises(InputError, match="valid storeys: 'L1', 'L2'"):
        site.storey("L9")
    assert math.isclose(load_site(tmp_path / "features.csv").storeys["L2"].features[0].y, 58.41)
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no features.csv"):
        load_site(tmp_path / "empty")


def test_format_features_has_no_negative_zero():
    text = format_features([Feature("a", "Door", 0, 0, -1e-17, -1.0, 1, 2)])
    assert "-0.000000" not in text
