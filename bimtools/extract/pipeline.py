"""``extract_site``: IFC file in, per-storey site model (features, floor plan, grid) out."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import ifcopenshell
import ifcopenshell.util.element
import ifcopenshell.util.placement
import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from bimkit.checks import check_number
from bimkit.errors import InputError
from bimtools.extract.candidates import (
    Candidates,
    ElementStoreys,
    collect_candidates,
    door_without_body,
    placement_axes,
)
from bimtools.extract.circulation import FreeRegions, SpaceIndex
from bimtools.extract.features import (
    BodyCandidate,
    DoorCandidate,
    StoreyContext,
    is_shaft_space,
    storey_features,
)
from bimtools.extract.floorplan import FloorPlan, ObstacleShape, build_floorplan
from bimtools.extract.landmarks import region_probe, storey_landmarks
from bimtools.extract.occupancy import rasterise
from bimtools.extract.placement import opening_in_plan
from bimtools.extract.section import polygons_of, projected_footprint, section_polygon
from bimtools.ifc.categories import CategorySet, load_categories
from bimtools.ifc.geometry import Mesh, ProgressCallback, iterate_meshes
from bimtools.ifc.model import ModelInfo, describe_model, open_model
from bimtools.ifc.storeys import Storey, list_storeys, storey_at_elevation
from bimtools.ifc.text import element_name
from bimtools.settings import (
    DEFAULT_RESOLUTION,
    DEFAULT_SECTION_HEIGHT,
    MAX_STOREY_ELEVATION,
    RESOLUTION_RANGE,
    SECTION_HEIGHT_RANGE,
    LandmarkSettings,
)
from bimtools.site.records import Feature, OccupancyGrid, camera_features

__all__ = [
    "BODY_BAND",
    "Candidates",
    "FLOOR_BAND",
    "FLOOR_CUT",
    "ExtractedSite",
    "GLASS_BAND",
    "GLASS_CLASSES",
    "LIFT_MIN_SPAN",
    "MERGE_DISTANCE",
    "StoreyResult",
    "extract_site",
    "merge_duplicates",
]

# Glazing: an obstacle over its whole plan footprint (a section at the cut meets only frame pieces).
GLASS_CLASSES = ("IfcWindow", "IfcCurtainWall", "IfcPlate")
GLASS_BAND = (-0.1, 2.5)  # metres around a storey's elevation whose vertices give a glass footprint
BODY_BAND = (-0.2, 2.2)  # metres around a storey's elevation where a lift/stair is "on" it
LIFT_MIN_SPAN = 1.8  # metres a lift body must reach above a storey's floor to serve it
MERGE_DISTANCE = 0.3  # metres: features closer than this are one element exported twice
# Floor slabs bound the building where its walls leave it open (gates standing open, a façade not
# yet built): a slab whose top lies this close (metres) to a storey's elevation is its floor.
FLOOR_BAND = (-0.6, 0.6)
FLOOR_CUT = 0.02  # metres below a slab's top where its plan footprint is cut


@dataclass
class StoreyResult:
    storey: Storey
    features: list[Feature]
    plan: FloorPlan
    grid: OccupancyGrid
    warnings: list[str] = field(default_factory=list)  # what the user should know (stderr)
    notes: list[str] = field(default_factory=list)  # what the extraction changed (summary)
    skipped: list[tuple[str, str]] = field(default_factory=list)  # (IFC class, why) of what was dropped


@dataclass
class ExtractedSite:
    info: ModelInfo
    section_height: float
    resolution: float
    storeys: list[StoreyResult] = field(default_factory=list)
    all_storeys: list[str] = field(default_factory=list)
    landmarks: LandmarkSettings | None = None  # the rules of the landmark rows (None: none extracted)

    warnings: list[str] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)  # (IFC class, why), all storeys

    def skipped_summary(self) -> str:
        """``5 IfcStair (its foot faces a wall), 2 IfcDoor (no geometry)``: each class and reason counted."""
        counts = Counter(self.skipped)
        ranked = sorted(counts.items(), key=lambda kv: -kv[1])
        return ", ".join(f"{n} {cls} ({why})" for (cls, why), n in ranked)

    @property
    def features(self) -> list[Feature]:
        return [f for s in self.storeys for f in s.features]

    @property
    def notes(self) -> list[str]:
        return [n for s in self.storeys for n in s.notes]


def _clamped_section(mesh: Mesh, z: float) -> BaseGeometry | None:
    zc = min(max(z, mesh.zmin + 0.02), mesh.zmax - 0.02)
    return section_polygon(mesh.verts, mesh.faces, zc)


def _band_points(verts: np.ndarray, lo: float, hi: float) -> np.ndarray:
    inside = verts[(verts[:, 2] >= lo) & (verts[:, 2] <= hi)]
    return inside[:, :2] if len(inside) else np.empty((0, 2))


def _area_points(area: BaseGeometry) -> np.ndarray:
    inner = area.buffer(-0.15)
    source = inner if not inner.is_empty else area
    pts = [np.asarray(source.representative_point().coords)[:, :2]]
    for poly in polygons_of(source):
        pts.append(np.asarray(poly.exterior.coords)[:, :2])
    return np.concatenate(pts)


def _stair_parts(element: ifcopenshell.entity_instance, meshes: dict[str, Mesh]) -> list[np.ndarray]:
    parts = [meshes[element.GlobalId].verts] if element.GlobalId in meshes else []
    for child in ifcopenshell.util.element.get_decomposition(element):
        if child.GlobalId in meshes:
            parts.append(meshes[child.GlobalId].verts)
    return parts


def extract_site(
    path: Path,
    categories: CategorySet | None = None,
    storey: str | None = None,
    section_height: float = DEFAULT_SECTION_HEIGHT,
    resolution: float = DEFAULT_RESOLUTION,
    progress: ProgressCallback | None = None,
    threads: int | None = None,
) -> ExtractedSite:
    """Extract features, floor plans and grids of the storeys of an IFC model.

    ``storey``: None = every storey that has features, ``"all"`` = every storey, else a name.
    """
    check_number(section_height, "--section-height", **SECTION_HEIGHT_RANGE)
    check_number(resolution, "--resolution", **RESOLUTION_RANGE)
    categories = categories or load_categories()
    model = open_model(path)
    info = describe_model(path, model)
    storeys = list_storeys(model, info.unit_scale)
    if not storeys:
        raise InputError(f"{path}: model has no storeys (IfcBuildingStorey)")
    _check_elevations(path, storeys)
    if storey not in (None, "all") and storey not in {s.name for s in storeys}:
        valid = ", ".join(repr(s.name) for s in storeys)
        raise InputError(f"{path}: no storey {storey!r}; valid storeys: {valid}")
    candidates = collect_candidates(model, categories)
    meshes = iterate_meshes(model, candidates.all(), progress=progress, threads=threads)
    where = ElementStoreys(storeys, meshes)

    result = ExtractedSite(
        info,
        section_height,
        resolution,
        all_storeys=[s.name for s in storeys],
        landmarks=categories.landmarks if categories.landmarks.enabled else None,
    )
    heights = _storey_heights(storeys, candidates, meshes)
    walls = 0
    for s in storeys:
        if storey not in (None, "all") and s.name != storey:
            continue
        storey_result = _extract_storey(
            s, storeys, candidates, meshes, where, categories, section_height, resolution, info.unit_scale
        )
        walls += len(storey_result.plan.walls)
        if section_height >= heights[s.name]:
            result.warnings.append(
                f"storey {s.name!r}: the section height {section_height:g} m is above the storey's height "
                f"({heights[s.name]:.2f} m); its plan has {len(storey_result.plan.walls)} walls"
            )
        result.warnings += storey_result.warnings
        result.skipped += storey_result.skipped
        if camera_features(storey_result.features) or storey is not None:
            result.storeys.append(storey_result)
    kinds = {c.name: c.kind for c in categories.categories}
    for element in candidates.bodies:  # a lift or stair with no geometry at all: no storey saw it
        parent = ifcopenshell.util.element.get_aggregate(element)
        if (parent is not None and parent.id() in candidates.body_category) or _stair_parts(element, meshes):
            continue
        kind = kinds[candidates.body_category[element.id()]]
        result.warnings.append(
            f"{kind} {element_name(element)!r} ({element.GlobalId}): no body, nor parts with one; skipped"
        )
        result.skipped.append((element.is_a(), "no geometry"))
    if walls == 0 and candidates.obstacles:
        raise InputError(
            f"{path}: --section-height {section_height:g} m cuts no wall on any storey "
            f"(the lowest storey is {min(heights.values()):.2f} m high); lower it"
        )
    if not camera_features(result.features):
        asked = "any storey" if storey in (None, "all") else f"storey {storey!r}"
        raise InputError(f"{path}: no features found (no doors, lifts or stairs on {asked})")
    return result


def _check_elevations(path: Path, storeys: list[Storey]) -> None:
    """Refuse a storey whose floor lies beyond +-MAX_STOREY_ELEVATION (a unit or export error)."""
    for s in storeys:
        if not abs(s.elevation) <= MAX_STOREY_ELEVATION:
            raise InputError(
                f"{path}: storey {s.name!r} has an elevation of {s.elevation:g} m, beyond "
                f"+-{MAX_STOREY_ELEVATION / 1000:g} km (a unit or export error in the model)"
            )


def _storey_heights(
    storeys: list[Storey], candidates: Candidates, meshes: dict[str, Mesh]
) -> dict[str, float]:
    """Each storey's height: up to the next storey's floor (0.5 m or more above), the top storey's
    up to the top of the highest wall, column, door or window (inf when the model has none)."""
    tops = [meshes[e.GlobalId].zmax for e in candidates.obstacles if e.GlobalId in meshes]
    heights: dict[str, float] = {}
    for s in storeys:
        above = [o.elevation for o in storeys if o.elevation > s.elevation + 0.5]
        top = min(above) if above else max(tops, default=math.inf)
        heights[s.name] = top - s.elevation if top > s.elevation else math.inf
    return heights


def _extract_storey(
    s: Storey,
    storeys: list[Storey],
    candidates: Candidates,
    meshes: dict[str, Mesh],
    where: ElementStoreys,
    categories: CategorySet,
    section_height: float,
    resolution: float,
    scale: float,
) -> StoreyResult:
    cut = s.elevation + section_height
    warnings: list[str] = []
    obstacles = _obstacles_at(s, cut, candidates, meshes)
    space_names, space_areas, space_entities = _spaces_at(s, cut, candidates, meshes, where)
    plan = build_floorplan(s.name, cut, obstacles, space_areas + _floors_at(s, candidates, meshes))
    grid, _ = rasterise(plan, resolution)
    ctx = StoreyContext(
        s.name, s.elevation, FreeRegions(grid), SpaceIndex(space_names, space_areas), categories
    )
    skipped: list[tuple[str, str]] = []
    doors = _doors_on(s, candidates, meshes, where, scale, warnings, skipped)
    bodies = _bodies_on_storey(s, storeys, candidates, meshes, where, categories)
    bodies += _shaft_spaces(space_entities, space_names, space_areas, categories)
    features = storey_features(ctx, doors, bodies)
    warnings += ctx.warnings
    skipped += ctx.skipped
    order = {c.name: i for i, c in enumerate(categories.categories)}
    features.sort(key=lambda f: (order.get(f.category, 99), round(f.x, 3), round(f.y, 3), f.id))
    features, notes = merge_duplicates(features)
    if categories.landmarks.enabled:
        free = region_probe(ctx.regions.label_at, ctx.regions.areas)
        features += storey_landmarks(plan.walls, categories.landmarks, s.name, s.elevation, free)
    return StoreyResult(s, features, plan, grid, warnings, notes, skipped)


def _spaces_at(
    s: Storey, cut: float, candidates: Candidates, meshes: dict[str, Mesh], where: ElementStoreys
) -> tuple[list[str], list[BaseGeometry], list]:
    """The storey's spaces cut at ``cut``: their names, section areas and entities."""
    space_names: list[str] = []
    space_areas: list[BaseGeometry] = []
    space_entities = []
    for space in candidates.spaces:
        mesh = meshes.get(space.GlobalId)
        if mesh is None or where.of(space) is not s:
            continue
        area = _clamped_section(mesh, cut)
        if area is None or area.is_empty:
            continue
        space_names.append(element_name(space))
        space_areas.append(area)
        space_entities.append(space)
    return space_names, space_areas, space_entities


def _floors_at(s: Storey, candidates: Candidates, meshes: dict[str, Mesh]) -> list[BaseGeometry]:
    """The plan footprints of the storey's floor slabs (their top within FLOOR_BAND of its
    elevation), cut just below their top: with the spaces they bound the building where its walls
    leave it open to the outside (a hall's gates, an unfinished façade)."""
    floors: list[BaseGeometry] = []
    lo, hi = s.elevation + FLOOR_BAND[0], s.elevation + FLOOR_BAND[1]
    for slab in candidates.slabs:
        mesh = meshes.get(slab.GlobalId)
        if mesh is None or not (lo <= mesh.zmax <= hi):
            continue
        z = mesh.zmax - min(FLOOR_CUT, (mesh.zmax - mesh.zmin) / 2)
        area = section_polygon(mesh.verts, mesh.faces, z)
        if area is not None and area.area > 1e-6:
            floors.append(area)
    return floors


def _doors_on(
    s: Storey,
    candidates: Candidates,
    meshes: dict[str, Mesh],
    where: ElementStoreys,
    scale: float,
    warnings: list[str],
    skipped: list[tuple[str, str]],
) -> list[DoorCandidate]:
    """The storey's doors with their openings in plan; a door without a body is placed from the
    opening it fills or its placement (a warning says which), one without any geometry skipped."""
    doors: list[DoorCandidate] = []
    for element in candidates.doors:
        if where.of(element) is not s:
            continue
        mesh = meshes.get(element.GlobalId)
        verts = mesh.verts if mesh is not None else door_without_body(element, candidates, meshes, scale)
        if verts is None:
            warnings.append(f"storey {s.name!r}: door {element_name(element)!r} has no geometry, skipped")
            skipped.append((element.is_a(), "no geometry"))
            continue
        if mesh is None:
            warnings.append(
                f"storey {s.name!r}: door {element_name(element)!r} ({element.GlobalId}) has no body; "
                + (
                    "placed from the opening it fills"
                    if element.GlobalId in candidates.openings
                    and candidates.openings[element.GlobalId].GlobalId in meshes
                    else "placed from its placement and OverallWidth"
                )
            )
        x_axis, y_axis = placement_axes(element)
        width = getattr(element, "OverallWidth", None)
        height = getattr(element, "OverallHeight", None)
        opening = opening_in_plan(
            verts, x_axis, y_axis, width * scale if width else None, height * scale if height else None
        )
        doors.append(DoorCandidate(element.GlobalId, element.is_a(), element_name(element), opening, element))
    return doors


def _shaft_spaces(
    entities: list, names: list[str], areas: list[BaseGeometry], categories: CategorySet
) -> list[BodyCandidate]:
    """Spaces that are lift or stair shafts by name and size (not circulation): bodies of their
    category (a lift's starts on this storey)."""
    bodies: list[BodyCandidate] = []
    for entity, name, area in zip(entities, names, areas, strict=True):
        for cat in categories.categories:
            if (
                cat.kind in ("lift", "stairs")
                and cat.is_space(name)
                and not categories.is_circulation(name)
                and is_shaft_space(cat, float(area.area))
            ):
                bodies.append(
                    BodyCandidate(
                        entity.GlobalId,
                        entity.is_a(),
                        name,
                        cat.name,
                        area,
                        _area_points(area),
                        starts_here=cat.kind == "lift",
                    )
                )
                break
    return bodies


def merge_duplicates(features: list[Feature]) -> tuple[list[Feature], list[str]]:
    """One feature per place: of features closer than MERGE_DISTANCE (an element exported twice,
    e.g. a storefront door again as a curtain-wall door) the first is kept (``features`` is in
    category order, so a Lift or Stairs entrance wins over a Door); a note says what went."""
    kept: list[Feature] = []
    notes: list[str] = []
    for f in features:
        twin = next((k for k in kept if math.hypot(k.x - f.x, k.y - f.y) < MERGE_DISTANCE), None)
        if twin is None:
            kept.append(f)
            continue
        notes.append(
            f"storey {f.storey!r}: {f.category} {f.name!r} ({f.id}) is "
            f"{math.hypot(twin.x - f.x, twin.y - f.y):.2f} m from {twin.category} {twin.name!r} "
            f"({twin.id}): merged into it"
        )
    return kept, notes


def _obstacles_at(
    s: Storey, cut: float, candidates: Candidates, meshes: dict[str, Mesh]
) -> list[ObstacleShape]:
    """Footprints at the cut: sections of solids; glazing projected whole (see GLASS_CLASSES)."""
    obstacles: list[ObstacleShape] = []
    for element in candidates.obstacles:
        mesh = meshes.get(element.GlobalId)
        if mesh is None or not (mesh.zmin < cut < mesh.zmax):
            continue
        glass = any(element.is_a(c) for c in GLASS_CLASSES)
        area = None
        if glass:
            lo, hi = s.elevation + GLASS_BAND[0], s.elevation + GLASS_BAND[1]
            area = projected_footprint(mesh.verts, lo, hi)
        if area is None:
            area = section_polygon(mesh.verts, mesh.faces, cut)
        if area is not None and area.area > 1e-6:
            obstacles.append(ObstacleShape(element.GlobalId, element.is_a(), area, glass))
    return obstacles


def _bodies_on_storey(
    s: Storey,
    storeys: list[Storey],
    candidates: Candidates,
    meshes: dict[str, Mesh],
    where: ElementStoreys,
    categories: CategorySet,
) -> list[BodyCandidate]:
    kinds = {c.name: c.kind for c in categories.categories}
    lo, hi = s.elevation + BODY_BAND[0], s.elevation + BODY_BAND[1]
    bodies: list[BodyCandidate] = []
    for element in candidates.bodies:
        category = candidates.body_category[element.id()]
        if kinds[category] == "stairs":
            parent = ifcopenshell.util.element.get_aggregate(element)
            if parent is not None and parent.id() in candidates.body_category:
                continue  # a flight of a stair: handled with its stair
            parts = _stair_parts(element, meshes)
        else:
            parts = [meshes[element.GlobalId].verts] if element.GlobalId in meshes else []
        if not parts:
            continue
        verts = np.concatenate(parts)
        zmin, zmax = float(verts[:, 2].min()), float(verts[:, 2].max())
        home = where.of(element)
        if kinds[category] == "lift":
            # A lift serves a storey when its car/shaft spans the storey's door height.
            on_storey = zmin <= s.elevation + 0.5 and zmax >= s.elevation + LIFT_MIN_SPAN
        else:
            on_storey = home is s or (zmin < hi and zmax > lo + 0.4)
        if not on_storey:
            continue
        points = _band_points(verts, lo, hi)
        if len(points) < 3:
            continue
        footprint = shapely.convex_hull(shapely.multipoints(points))
        starts_here = storey_at_elevation(storeys, zmin) is s
        bodies.append(
            BodyCandidate(
                element.GlobalId,
                element.is_a(),
                element_name(element),
                category,
                footprint,
                points,
                parts=parts,
                starts_here=starts_here,
                height=min(zmax - zmin, 2.1) if zmax > zmin else 2.1,
            )
        )
    return bodies
