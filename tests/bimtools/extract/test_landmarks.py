"""bimtools.extract.landmarks: wall corners, column corners and openings from the wall surfaces."""

from __future__ import annotations

import csv
import dataclasses
import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon, box

from bimtools.extract.floorplan import ObstacleShape, build_floorplan
from bimtools.extract.landmarks import LINE_TOLERANCE, chain_rings, storey_landmarks, wall_landmarks
from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.ifc.categories import load_categories
from bimtools.settings import LandmarkSettings
from bimtools.site.features_csv import format_features
from bimtools.site.load import load_site
from bimtools.site.records import FREE, LANDMARK_CATEGORIES
from tests.helpers import SAMPLES, SCHEMAS
from tests.landmark_worlds import SETTINGS, corridor_with_door, l_room, room_with, walled


def _at(found, category: str) -> list[tuple[float, float]]:
    return sorted((round(m.x, 3) + 0.0, round(m.y, 3) + 0.0) for m in found if m.category == category)


def test_l_room_has_five_concave_and_one_convex_corner_with_bisector_normals() -> None:
    found = l_room().truth()
    assert _at(found, "ConcaveCorner") == [(0, 0), (0, 8), (4, 8), (8, 0), (8, 4)]
    assert _at(found, "ConvexCorner") == [(4, 4)]
    by_place = {(round(m.x), round(m.y)): m for m in found}
    h = math.sqrt(0.5)
    assert by_place[(0, 0)].normal == pytest.approx((h, h))  # into the room
    assert by_place[(4, 4)].normal == pytest.approx((-h, -h))  # out of the corner, into the room
    assert {m.name for m in found} == {"concave corner 90 deg", "convex corner 90 deg"}


def test_without_the_free_probe_the_outside_corners_come_too() -> None:
    world = l_room()
    inside = wall_landmarks(world.plan.walls, SETTINGS, world.free)
    everywhere = wall_landmarks(world.plan.walls, SETTINGS)
    assert len(everywhere) == 2 * len(inside)  # the outer face of the L has as many corners


@pytest.mark.parametrize(("recess", "expected"), [(None, 2), (0.08, 2), (0.02, 1)])
def test_a_doorway_or_a_recessed_leaf_is_an_opening(recess, expected) -> None:
    """A door gap 0.9 m wide: open, or closed by a leaf 8 cm back (an opening on both sides), or
    2 cm back (below min_recess on the corridor side: wall to a lidar; 14 cm back from the room)."""
    openings = [m for m in corridor_with_door(recess).truth() if m.category == "Opening"]
    assert len(openings) == expected
    for m in openings:
        assert (m.x, m.width) == pytest.approx((6.0, 0.9))
        assert m.y == pytest.approx(2.0 if m.normal[1] < 0 else 2.2)
        assert abs(m.normal[1]) == pytest.approx(1.0)
    if recess is None:
        assert all("through" in m.name for m in openings)


@pytest.mark.parametrize("gap", [0.5, 3.0])
def test_gaps_outside_door_widths_are_no_openings(gap) -> None:
    assert not [m for m in corridor_with_door(gap=gap).truth() if m.category == "Opening"]


def test_a_small_free_standing_column_gives_column_corners_a_big_pillar_convex_ones() -> None:
    column = room_with(box(3.8, 2.8, 4.2, 3.2)).truth()
    assert _at(column, "ColumnCorner") == [(3.8, 2.8), (3.8, 3.2), (4.2, 2.8), (4.2, 3.2)]
    pillar = room_with(box(3, 2, 4.5, 3.5)).truth()
    assert _at(pillar, "ColumnCorner") == []
    assert len(_at(pillar, "ConvexCorner")) == 4


def test_short_faces_are_no_corners() -> None:
    """A box of 0.25 m (clutter), a 5 cm jog in a wall and a moulding give no corner (min_leg)."""
    clutter = room_with(box(5, 2, 5.25, 2.25)).truth()
    assert _at(clutter, "ColumnCorner") == _at(clutter, "ConvexCorner") == []
    jog = walled(Polygon([(0, 0), (4, 0), (4, 0.05), (8, 0.05), (8, 6), (0, 6)])).truth()
    assert _at(jog, "ConcaveCorner") == [(0, 0), (0, 6), (8, 0.05), (8, 6)]
    assert _at(jog, "ConvexCorner") == []


def test_corner_angle_range_is_applied() -> None:
    wedge = walled(Polygon([(0, 0), (6, 0), (0, 6 * math.tan(math.radians(40)))]))  # 40 and 50 deg corners
    assert _at(wedge.truth(), "ConcaveCorner") == [(0, 0)]
    wide = dataclasses.replace(SETTINGS, corner_angle=(30.0, 150.0))
    assert len(_at(wedge.truth(wide), "ConcaveCorner")) == 3


def test_glass_faces_are_no_corners() -> None:
    """A room whose east wall is glazed: the two corners on it are seen by a lidar through the glass."""
    shapes = [
        ObstacleShape("s", "IfcWall", box(-0.2, -0.2, 4.2, 0)),
        ObstacleShape("n", "IfcWall", box(-0.2, 4, 4.2, 4.2)),
        ObstacleShape("w", "IfcWall", box(-0.2, 0, 0, 4)),
        ObstacleShape("e", "IfcWindow", box(4, 0, 4.2, 4), glass=True),
    ]
    plan = build_floorplan("L", 1.0, shapes, [box(0, 0, 4, 4)])
    inside = lambda x, y: 0 < x < 4 and 0 < y < 4  # noqa: E731
    assert _at(wall_landmarks(plan.walls, SETTINGS, inside), "ConcaveCorner") == [(0, 0), (0, 4)]


def test_ids_are_stable_unique_and_name_the_wall() -> None:
    world = corridor_with_door(0.08)
    walls = world.plan.walls
    rows = storey_landmarks(walls, SETTINGS, "L", 0.0, world.free)
    again = storey_landmarks(list(reversed(walls)), SETTINGS, "L", 0.0, world.free)
    assert [r.id for r in rows] == [r.id for r in again]
    assert len({r.id for r in rows}) == len(rows)
    elements = {w.element for w in walls}
    for r in rows:
        element, code = r.id.rsplit("-", 1)
        assert element in elements and code[:2] in ("CC", "CX", "CO", "OP") and code[2:].isdigit()
        assert r.height == 0.0 and r.ifc_class == "IfcWall" and r.sensor == "lidar"
    order = [r.category for r in rows]
    assert order == sorted(order, key=["ConcaveCorner", "ConvexCorner", "ColumnCorner", "Opening"].index)


def test_rings_chain_closed() -> None:
    rings = chain_rings(l_room().plan.walls)
    assert len(rings) == 2 and all(closed for _, closed in rings)  # the inner and the outer face


def test_off_gives_nothing_and_an_empty_plan_nothing() -> None:
    assert not LandmarkSettings().enabled
    assert storey_landmarks([], SETTINGS, "L", 0.0) == []
    assert wall_landmarks(l_room().plan.walls, dataclasses.replace(SETTINGS, min_leg=9.0)) == []


def test_corners_lie_on_wall_vertices() -> None:
    world = room_with(box(3.8, 2.8, 4.2, 3.2))
    ends = np.array([[w.x1, w.y1] for w in world.plan.walls])
    for m in world.truth():
        assert np.min(np.hypot(*(ends - [m.x, m.y]).T)) < 1e-6


# --- on a sample model, through the pipeline -----------------------------------------------------


@functools.cache
def _hallway(enabled: bool | None):
    """ntu_hallway extracted with the shipped categories (None) or landmarks switched on or off."""
    categories = load_categories()
    if enabled is not None:
        categories = dataclasses.replace(categories, landmarks=LandmarkSettings(enabled=enabled))
    return extract_site(SAMPLES / "ntu_hallway.ifc", categories)


def test_switched_off_the_feature_table_is_the_camera_table_byte_for_byte(tmp_path: Path) -> None:
    shipped, off, on = (format_features(_hallway(e).features) for e in (None, False, True))
    assert shipped == off
    camera = [f for f in _hallway(True).features if f.sensor == "camera"]
    assert format_features(camera) == off  # the same rows in the same order, landmarks after them
    assert len(on.splitlines()) > len(off.splitlines()) + 50
    rows = _hallway(True).features
    first_landmark = next(i for i, f in enumerate(rows) if f.sensor == "lidar")
    assert all(f.sensor == "lidar" for f in rows[first_landmark:])


def test_sample_landmarks_lie_on_the_walls_and_face_free_floor() -> None:
    """Corners are vertices of the wall section, openings lie on a wall line; a point 0.3 m along
    every normal is a free cell of the map."""
    (result,) = _hallway(True).storeys
    ends = np.array([[w.x1, w.y1] for w in result.plan.walls] + [[w.x2, w.y2] for w in result.plan.walls])
    lines = shapely.MultiLineString([[(w.x1, w.y1), (w.x2, w.y2)] for w in result.plan.walls])
    landmarks = [f for f in result.features if f.sensor == "lidar"]
    assert {f.category for f in landmarks} >= {"ConcaveCorner", "ConvexCorner", "Opening"}
    for f in landmarks:
        if f.category == "Opening":
            assert 0.7 <= f.width <= 2.5
            gap_ends = [(f.x + s * f.norm_y * f.width / 2, f.y - s * f.norm_x * f.width / 2) for s in (-1, 1)]
            assert max(lines.distance(shapely.Point(p)) for p in gap_ends) < LINE_TOLERANCE
        else:
            assert np.min(np.hypot(*(ends - [f.x, f.y]).T)) < 1e-6
        assert result.grid.value_at(f.x + 0.3 * f.norm_x, f.y + 0.3 * f.norm_y) == FREE, f


def test_site_folder_with_landmarks_validates_loads_and_splits_by_sensor(tmp_path: Path) -> None:
    import jsonschema

    out = tmp_path / "site"
    write_site(out, _hallway(True))
    schema = json.loads((SCHEMAS / "features.schema.json").read_text())
    numbers = ("X", "Y", "Norm_X", "Norm_Y", "Width", "Height", "Elevation")
    with open(out / "features.csv", encoding="utf-8") as handle:
        for row in csv.DictReader(handle):
            jsonschema.validate({k: float(v) if k in numbers else v for k, v in row.items()}, schema)
    site = load_site(out)
    (storey,) = site.storeys.values()
    assert storey.camera_features == [f for f in storey.features if f.category in ("Door", "Lift", "Stairs")]
    assert {f.category for f in storey.lidar_landmarks} <= set(LANDMARK_CATEGORIES)
    assert len(storey.camera_features) + len(storey.lidar_landmarks) == len(storey.features)
    doc = json.loads((out / "site.json").read_text())
    jsonschema.validate(doc, json.loads((SCHEMAS / "site.schema.json").read_text()))
    counts = doc["storeys"][0]["counts"]
    assert counts["ConcaveCorner"] == sum(f.category == "ConcaveCorner" for f in storey.features)
    # the rules travel with the site, for reading scans by them
    assert site.manifest is not None and site.manifest.landmarks == LandmarkSettings(enabled=True)
    assert doc["landmarks"]["corner_angle"] == [60.0, 120.0]
    off = tmp_path / "off"
    write_site(off, _hallway(False), preview=False)
    assert "landmarks" not in json.loads((off / "site.json").read_text())
    assert load_site(off).manifest.landmarks is None
