"""``bim-extract MAP.yaml``: any Nav2 map is a site (one storey, the map as given, walls from the
occupied cells, features from --features or none), and the robot side reads it."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml

from bimkit.errors import InputError
from bimtools.extract.from_map import (
    extract_map_site,
    grid_obstacles,
    grid_walls,
    is_map_file,
    read_map_features,
    write_map_site,
)
from bimtools.site.features_csv import read_features
from bimtools.site.load import load_site
from bimtools.site.occupancy_map import FREE, OCCUPIED, UNKNOWN, OccupancyGrid, read_map
from bimtools.site.records import TABLE1_COLUMNS
from tests.bimtools.test_cli import assert_bad_input, run_extract

RES = 0.1
ORIGIN = (-2.0, -1.0, 0.0)


def corridor_cells() -> np.ndarray:
    """A 16 m x 9 m floor: a corridor along y = 4..6 m with three rooms below, two above, doorways
    into each, walls 0.2 m thick, unknown outside."""
    rows, cols = 100, 170
    cells = np.full((rows, cols), UNKNOWN, dtype=np.uint8)
    cells[5:95, 5:165] = OCCUPIED
    cells[7:93, 7:163] = FREE

    def wall_row(r: int, c0: int, c1: int) -> None:
        cells[r : r + 2, c0:c1] = OCCUPIED

    def wall_col(c: int, r0: int, r1: int) -> None:
        cells[r0:r1, c : c + 2] = OCCUPIED

    wall_row(35, 7, 163)  # corridor's upper wall (rows 35-36)
    wall_row(55, 7, 163)  # corridor's lower wall (rows 55-56)
    for c in (60, 110):
        wall_col(c, 57, 93)  # rooms below
    wall_col(90, 7, 35)  # rooms above
    for c0 in (20, 80, 130):
        cells[55:57, c0 : c0 + 9] = FREE  # doorways below
    for c0 in (40, 120):
        cells[35:37, c0 : c0 + 9] = FREE  # doorways above
    cells[40:43, 140:143] = OCCUPIED  # a column in the corridor
    return cells


def write_map_files(folder: Path, cells: np.ndarray, name: str = "corridor", **meta: object) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    rows, cols = cells.shape
    (folder / f"{name}.pgm").write_bytes(f"P5\n{cols} {rows}\n255\n".encode() + cells.tobytes())
    doc = {
        "image": f"{name}.pgm",
        "mode": "trinary",
        "resolution": RES,
        "origin": list(ORIGIN),
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
        **meta,
    }
    (folder / f"{name}.yaml").write_text(yaml.safe_dump(doc))
    return folder / f"{name}.yaml"


def test_walls_of_one_occupied_cell():
    cells = np.full((3, 3), FREE, dtype=np.uint8)
    cells[1, 1] = OCCUPIED
    walls = grid_walls(OccupancyGrid(cells, 1.0, (10.0, 20.0, 0.0)), "S")
    sides = {(w.normal, (w.x1, w.y1, w.x2, w.y2)) for w in walls}
    assert sides == {
        ((0.0, 1.0), (11.0, 22.0, 12.0, 22.0)),
        ((0.0, -1.0), (11.0, 21.0, 12.0, 21.0)),
        ((-1.0, 0.0), (11.0, 21.0, 11.0, 22.0)),
        ((1.0, 0.0), (12.0, 21.0, 12.0, 22.0)),
    }
    obstacles = grid_obstacles(OccupancyGrid(cells, 1.0, (10.0, 20.0, 0.0)), "S")
    assert len(obstacles) == 1 and not obstacles[0].holes
    assert {tuple(p) for p in obstacles[0].exterior} == {
        (11.0, 21.0),
        (12.0, 21.0),
        (12.0, 22.0),
        (11.0, 22.0),
    }


def test_walls_face_free_cells_only_and_join_runs():
    cells = corridor_cells()
    grid = OccupancyGrid(cells, RES, ORIGIN)
    walls = grid_walls(grid, "corridor")
    # every wall has free space on its normal side and an occupied cell behind it
    for w in walls:
        mx, my = (w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2
        assert grid.value_at(mx + 0.5 * RES * w.normal[0], my + 0.5 * RES * w.normal[1]) == FREE
        assert grid.value_at(mx - 0.5 * RES * w.normal[0], my - 0.5 * RES * w.normal[1]) == OCCUPIED
    # the outer faces (towards unknown) are no surface; the column has four sides of 0.3 m
    column = [w for w in walls if math.isclose(w.length, 0.3) and -2 + 14 <= w.x1 <= -2 + 14.3]
    assert len(column) == 4
    # the corridor's upper wall, free above (rooms) and below (corridor), broken by two doorways
    total = sum(w.length for w in walls)
    assert 120 < total < 200
    obstacles = grid_obstacles(grid, "corridor")
    area = sum(abs(_area(o.exterior)) - sum(abs(_area(h)) for h in o.holes) for o in obstacles)
    assert math.isclose(area, float((cells == OCCUPIED).sum()) * RES * RES, rel_tol=1e-9)


def _area(ring: tuple[tuple[float, float], ...]) -> float:
    xy = np.asarray(ring)
    return 0.5 * float(np.dot(xy[:-1, 0], xy[1:, 1]) - np.dot(xy[1:, 0], xy[:-1, 1]))


def test_cli_writes_a_site_the_robot_side_loads(tmp_path):
    cells = corridor_cells()
    yaml_path = write_map_files(tmp_path / "maps", cells)
    result = run_extract(str(yaml_path), "-o", str(tmp_path / "site"), "--json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    manifest = json.loads(result.stdout)
    assert [s["name"] for s in manifest["storeys"]] == ["corridor"]
    assert manifest["source"]["file"] == "corridor.yaml" and manifest["resolution"] == RES
    site_dir = tmp_path / "site"
    assert sorted(p.name for p in site_dir.iterdir() if not p.name.startswith(".")) == [
        "features.csv",
        "map_corridor.pgm",
        "map_corridor.yaml",
        "preview_corridor.png",
        "site.json",
        "walls.geojson",
    ]
    assert (site_dir / "features.csv").read_text().splitlines()[0].startswith(",".join(TABLE1_COLUMNS))
    assert len((site_dir / "features.csv").read_text().splitlines()) == 1
    site = load_site(site_dir)
    storey = site.storey("corridor")
    assert storey.features == [] and storey.walls and storey.obstacles
    assert storey.grid is not None and np.array_equal(storey.grid.cells, cells)
    assert storey.grid.origin == ORIGIN
    # the map as written is the map as given
    assert np.array_equal(read_map(site_dir / "map_corridor.yaml").cells, read_map(yaml_path).cells)
    schemas = Path(__file__).resolve().parents[3] / "bimkit" / "schemas"
    for name, schema in (("site.json", "site"), ("walls.geojson", "walls")):
        doc = json.loads((site_dir / name).read_text())
        jsonschema.validate(doc, json.loads((schemas / f"{schema}.schema.json").read_text()))
    map_doc = yaml.safe_load((site_dir / "map_corridor.yaml").read_text())
    jsonschema.validate(map_doc, json.loads((schemas / "map.schema.json").read_text()))


def test_negated_map_is_the_same_site(tmp_path):
    cells = corridor_cells()
    plain = extract_map_site(write_map_files(tmp_path / "a", cells))
    negated = extract_map_site(write_map_files(tmp_path / "b", (255 - cells).astype(np.uint8), negate=1))
    assert np.array_equal(plain.grid.cells, negated.grid.cells)
    assert plain.walls == negated.walls


def test_features_are_copied_in(tmp_path):
    yaml_path = write_map_files(tmp_path / "maps", corridor_cells())
    csv = tmp_path / "doors.csv"
    csv.write_text(
        ",".join(TABLE1_COLUMNS) + "\n" + "D1,door,1.0,4.0,0,1,0.9,2.1\n" + "L1,Lift,6.0,4.0,0,1,1.1,2.1\n"
    )
    result = run_extract(str(yaml_path), "-o", str(tmp_path / "site"), "--features", str(csv), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    features = read_features(tmp_path / "site" / "features.csv")
    assert [(f.id, f.category, f.storey) for f in features] == [
        ("D1", "Door", "corridor"),
        ("L1", "Lift", "corridor"),
    ]
    site = load_site(tmp_path / "site")
    assert [f.id for f in site.storey("corridor").camera_features] == ["D1", "L1"]
    doc = json.loads((tmp_path / "site" / "site.json").read_text())
    assert doc["storeys"][0]["counts"] == {"Door": 1, "Lift": 1}


@pytest.mark.parametrize(
    ("rows", "says"),
    [
        ("D1,Window,1,4,0,1,0.9,2.1\n", "doors.csv:2: column Category: unknown category 'Window'"),
        (
            "D1,Door,1,4,0,1,0.9,2.1\nD1,Door,2,4,0,1,0.9,2.1\n",
            "doors.csv:3: ID D1 on storey '' is on line 2 already",
        ),
        ("D1,Door,one,4,0,1,0.9,2.1\n", "doors.csv:2: column X: expected a number, got 'one'"),
        ("D1,Door,100,4,0,1,0.9,2.1\n", "doors.csv:2: (100, 4) lies outside the map"),
    ],
)
def test_bad_features_name_file_and_line(tmp_path, rows, says):
    csv = tmp_path / "doors.csv"
    csv.write_text(",".join(TABLE1_COLUMNS) + "\n" + rows)
    grid = OccupancyGrid(corridor_cells(), RES, ORIGIN)
    with pytest.raises(InputError) as caught:
        read_map_features(csv, "corridor", grid, ("Door", "Lift", "Stairs"))
    assert says in str(caught.value)


def test_cli_refusals_are_one_line_before_any_output(tmp_path):
    cells = corridor_cells()
    csv = tmp_path / "doors.csv"
    csv.write_text(",".join(TABLE1_COLUMNS) + "\nD1,Door,1,4,0,1,0.9,2.1\nD1,Door,2,4,0,1,0.9,2.1\n")
    out = str(tmp_path / "out")
    yaw = write_map_files(tmp_path / "yaw", cells, origin=[0.0, 0.0, 0.3])
    assert_bad_input(run_extract(str(yaw), "-o", out, cwd=tmp_path), "corridor.yaml", "origin yaw 0.3")
    good = write_map_files(tmp_path / "good", cells)
    sheared = tmp_path / "good" / "corridor.pgm"
    data = sheared.read_bytes()
    sheared.write_bytes(data.replace(b"170 100", b"169 100", 1))
    assert_bad_input(run_extract(str(good), "-o", out, cwd=tmp_path), "corridor.pgm", "header disagrees")
    sheared.write_bytes(data)
    assert_bad_input(
        run_extract(str(good), "-o", out, "--features", str(csv), cwd=tmp_path),
        "doors.csv:3",
        "is on line 2 already",
    )
    # the output folder may not hold the map it reads
    assert_bad_input(run_extract(str(good), "-o", str(tmp_path), cwd=tmp_path), "holds the input")
    assert not (tmp_path / "out").exists()


def test_features_option_is_for_maps(tmp_path):
    model = tmp_path / "x.ifc"
    model.write_text("ISO-10303-21;\n")
    csv = tmp_path / "doors.csv"
    csv.write_text(",".join(TABLE1_COLUMNS) + "\n")
    result = run_extract(str(model), "--features", str(csv), "-o", str(tmp_path / "o"), cwd=tmp_path)
    assert_bad_input(result, "--features", "applies to a map")


def test_map_detection(tmp_path):
    assert is_map_file(tmp_path / "any.YML")
    (tmp_path / "map.txt").write_text("image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    (tmp_path / "model.dat").write_text("ISO-10303-21;\nimage:\nresolution:\n")
    assert is_map_file(tmp_path / "map.txt") and not is_map_file(tmp_path / "model.dat")


def test_round_trip_of_the_sample_map(site_a, tmp_path):
    """block_a's extracted map made a site again: the same cells, resolution and origin."""
    [yaml_path] = sorted(site_a.glob("map_*.yaml"))
    site = extract_map_site(yaml_path)
    write_map_site(tmp_path / "site", site, preview=False)
    back = load_site(tmp_path / "site").storey(yaml_path.stem).grid
    given = read_map(yaml_path)
    assert back is not None and np.array_equal(back.cells, given.cells)
    assert back.resolution == given.resolution and back.origin == given.origin
    raw = (site_a / yaml_path.with_suffix(".pgm").name).read_bytes()
    assert (tmp_path / "site" / f"map_{yaml_path.stem}.pgm").read_bytes() == raw


def test_survey_runs_on_a_map_site(tmp_path):
    """bim-init survey on a map site without features: the camera places no start, the lidar
    registration places those whose loop passes the doorways and the column (the rest of the
    corridor is alike), and the shut-in rooms and the lidar twins are found from the map alone."""
    yaml_path = write_map_files(tmp_path / "maps", corridor_cells())
    write_map_site(tmp_path / "site", extract_map_site(yaml_path), preview=False)
    result = subprocess.run(
        [
            sys.executable,
            "-c",
            "from initcli.cli.main import main; main()",
            "survey",
            str(tmp_path / "site"),
            "--out",
            str(tmp_path / "survey"),
            "--spacing",
            "2",
            "--headings",
            "2",
            "--landmarks",
            "0",
            "--workers",
            "1",
        ],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    [storey] = json.loads((tmp_path / "survey" / "survey.json").read_text())["storeys"]
    assert storey["storey"] == "corridor" and storey["samples"] > 0
    placed = storey["lidar_placed_share"]
    assert 0.0 < placed < 1.0
    assert storey["never_unique_share"] == pytest.approx(1.0 - placed)  # the lidar alone places any
