"""Extraction on real IFC models from other authors (../shared/ifc): geometry-first rules.

Skips cleanly when ../shared/ifc is absent.
"""

from __future__ import annotations

import functools
import math
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from bimtools.extract.pipeline import MERGE_DISTANCE, ExtractedSite
from bimtools.site.records import FREE, OCCUPIED
from tests.helpers import extracted_all_storeys, shared_ifc_files

NAMES = [p.name for p in shared_ifc_files()] or ["(none)"]
PROBES = (0.35, 0.6, 0.9, 1.3)  # metres along a feature's normal
# Storeys still open to the outside on the map (not glazing; left for a later change).
OPEN_FACADES = {
    ("AC20-Institute-Var-2.ifc", "Erdgeschoss"),
    ("ExampleHOM.ifc", "GroundFloor"),
    ("LiNear_Office_Building_Architectural_IFC_export.ifc", "Erdgeschoss"),
    ("LiNear_Office_Building_Architectural_IFC_export.ifc", "1. Obergeschoss"),
    ("LiNear_Office_Building_Architectural_IFC_export.ifc", "2. Obergeschoss"),
}
LIFT_WORDS = re.compile(r"lift|elev|aufzug|ascenseur|elevador", re.IGNORECASE)


def extracted(path: Path) -> ExtractedSite:
    return extracted_all_storeys(path)


def _site(shared_ifc_dir: Path, name: str) -> ExtractedSite:
    path = shared_ifc_dir / name
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    return extracted(path)


@pytest.mark.parametrize("name", NAMES)
def test_no_feature_normal_points_outside(shared_ifc_dir, name):
    for result in _site(shared_ifc_dir, name).storeys:
        grid = result.grid
        for f in result.features:
            ahead = [grid.value_at(f.x + t * f.norm_x, f.y + t * f.norm_y) for t in PROBES]
            assert FREE in ahead, f"{result.storey.name}: {f.category} {f.name!r} faces out of the building"


@pytest.mark.parametrize("name", NAMES)
def test_no_door_or_stair_faces_a_wall(shared_ifc_dir, name):
    """The floor right in front of every door and stair foot is open: no wall cell in the first
    0.35 m along its normal (a stair foot read from a turning stair's whole body faced into the
    stairwell's wall, its normal through it into the next room). A lift placed from its shaft's
    outline stands behind the shaft wall, so lifts are not held to this."""
    for result in _site(shared_ifc_dir, name).storeys:
        grid = result.grid
        for f in (f for f in result.features if f.category in ("Door", "Stairs")):
            ahead = [
                grid.value_at(f.x + t * f.norm_x, f.y + t * f.norm_y) for t in np.arange(0.1, 0.36, 0.05)
            ]
            assert OCCUPIED not in ahead, f"{result.storey.name}: {f.category} {f.name!r} faces a wall"


@pytest.mark.parametrize("name", NAMES)
def test_no_two_features_at_the_same_place(shared_ifc_dir, name):
    for result in _site(shared_ifc_dir, name).storeys:
        fs = result.features
        for i, a in enumerate(fs):
            for b in fs[i + 1 :]:
                d = math.hypot(a.x - b.x, a.y - b.y)
                assert d >= MERGE_DISTANCE, f"{result.storey.name}: {a.name!r} and {b.name!r} {d:.2f} m apart"


@functools.cache
def lift_spaces(path: Path) -> list:
    """Plan footprints (convex hulls) of the IfcSpaces named like a lift."""
    import ifcopenshell
    import ifcopenshell.geom
    import shapely

    model = ifcopenshell.open(str(path))
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    hulls = []
    for space in model.by_type("IfcSpace"):
        if LIFT_WORDS.search(f"{space.Name or ''} {space.LongName or ''}"):
            verts = np.asarray(ifcopenshell.geom.create_shape(settings, space).geometry.verts).reshape(-1, 3)
            hulls.append(shapely.convex_hull(shapely.multipoints(verts[:, :2])))
    return hulls


@pytest.mark.parametrize("name", NAMES)
def test_no_lift_without_lift_evidence(shared_ifc_dir, name):
    # Evidence: a lift-named element (elevator door, shaft space) or a door whose back opens into
    # a lift-named space (the extraction also requires that space to be shaft-sized).
    import shapely

    for f in _site(shared_ifc_dir, name).features:
        if f.category != "Lift" or LIFT_WORDS.search(f.name):
            continue
        behind = shapely.Point(f.x - 0.6 * f.norm_x, f.y - 0.6 * f.norm_y)
        assert any(h.buffer(0.3).contains(behind) for h in lift_spaces(shared_ifc_dir / name)), (
            f"{f.storey}: Lift {f.name!r} ({f.ifc_class}) without lift evidence"
        )


@pytest.mark.parametrize("name", NAMES)
def test_facade_is_closed_on_the_map(shared_ifc_dir, name):
    """From where a robot sees each feature, no path through non-occupied cells leaves the map."""
    for result in _site(shared_ifc_dir, name).storeys:
        if (name, result.storey.name) in OPEN_FACADES:
            continue
        grid = result.grid
        passable = (grid.cells != OCCUPIED).astype(np.uint8)
        _, labels = cv2.connectedComponents(passable, connectivity=4)
        edge = set(np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]).tolist()))
        for f in result.features:
            row, col = grid.world_to_cell(f.x + 0.6 * f.norm_x, f.y + 0.6 * f.norm_y)
            if grid.cells[row, col] != FREE:
                continue
            assert int(labels[row, col]) not in edge, (
                f"{result.storey.name}: from {f.category} {f.name!r} a robot drives out of the building"
            )


def test_office_a_exterior_doors_face_inside(shared_ifc_dir):
    site = _site(shared_ifc_dir, "Office_A_20110811.ifc")
    assert {s.storey.name for s in site.storeys} >= {"Level 1", "Level 2"}
    for result in site.storeys:
        for f in result.features:
            behind = [result.grid.value_at(f.x - t * f.norm_x, f.y - t * f.norm_y) for t in PROBES]
            ahead = [result.grid.value_at(f.x + t * f.norm_x, f.y + t * f.norm_y) for t in PROBES]
            if FREE not in behind:  # an exterior door: the robot can only be inside
                assert FREE in ahead, f.name


def test_digitalhub_passages_without_body_are_placed_with_a_warning(shared_ifc_dir):
    import ifcopenshell

    site = _site(shared_ifc_dir, "FM_ARC_DigitalHub.ifc")
    model = ifcopenshell.open(str(shared_ifc_dir / "FM_ARC_DigitalHub.ifc"))
    passages = [d for d in model.by_type("IfcDoor") if d.Representation is None]
    assert len(passages) == 6 and all("Durchgang" in d.Name for d in passages)
    rows = {f.id: f for f in site.features}
    for door in passages:
        assert door.GlobalId in rows, door.Name
        assert any(door.GlobalId in w for w in site.warnings), door.GlobalId
        f = rows[door.GlobalId]
        assert f.width == pytest.approx(1.2, abs=0.01)


@pytest.mark.parametrize("name", NAMES)
def test_lidar_landmarks_lie_on_the_walls_and_face_free_floor(shared_ifc_dir, name):
    """The landmark rules on the storeys of a real model (computed from the extraction's wall
    surfaces, as bim-extract does with landmarks on): corners are vertices of the wall section,
    an opening's two edges lie on wall lines, and 0.3 m along every normal is a free cell."""
    from bimtools.extract.circulation import FreeRegions
    from bimtools.extract.landmarks import LINE_TOLERANCE, region_probe, storey_landmarks
    from bimtools.settings import LandmarkSettings

    settings = LandmarkSettings(enabled=True)
    total = 0
    for result in _site(shared_ifc_dir, name).storeys:
        walls = result.plan.walls
        regions = FreeRegions(result.grid)
        rows = storey_landmarks(
            walls, settings, result.storey.name, 0.0, region_probe(regions.label_at, regions.areas)
        )
        total += len(rows)
        assert len({r.id for r in rows}) == len(rows)
        ends = np.array([[w.x1, w.y1] for w in walls]).reshape(-1, 2)
        lines = [((w.x1, w.y1), (w.x2, w.y2)) for w in walls]
        for f in rows:
            assert result.grid.value_at(f.x + 0.3 * f.norm_x, f.y + 0.3 * f.norm_y) == FREE, f
            if f.category != "Opening":
                assert float(np.min(np.hypot(*(ends - [f.x, f.y]).T))) < 1e-6, f
                continue
            assert settings.opening_width[0] <= f.width <= settings.opening_width[1]
            for s in (-1.0, 1.0):
                px, py = f.x + s * f.norm_y * f.width / 2, f.y - s * f.norm_x * f.width / 2
                assert min(_to_line(px, py, a, b) for a, b in lines) < LINE_TOLERANCE, f
    assert total > 0


def _to_line(px: float, py: float, a: tuple[float, float], b: tuple[float, float]) -> float:
    ex, ey = b[0] - a[0], b[1] - a[1]
    s = max(0.0, min(1.0, ((px - a[0]) * ex + (py - a[1]) * ey) / max(ex * ex + ey * ey, 1e-18)))
    return math.hypot(a[0] + s * ex - px, a[1] + s * ey - py)
