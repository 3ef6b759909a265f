"""A storey's floor plan at the section height: obstacle footprints, building outline, wall surfaces.

Wall surfaces are the boundary of the union of all obstacle footprints, split into straight
pieces, each attributed to the element it lies on, with the normal pointing away from the solid
into free space (the boundaries of the paper's Eq. 17).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import shapely
from shapely.geometry import LinearRing, Polygon
from shapely.geometry.base import BaseGeometry
from shapely.geometry.polygon import orient

from bimtools.extract.section import polygons_of
from bimtools.site.records import Obstacle, WallSegment

__all__ = ["FloorPlan", "ObstacleShape", "build_floorplan", "building_outline", "fill_holes", "wall_surfaces"]

_CLOSING = 0.35  # metres: gaps in the envelope up to twice this are closed for the outline
_COLLINEAR = math.radians(1.0)
_SLIVER = 2e-4  # metres


@dataclass
class ObstacleShape:
    element: str
    ifc_class: str
    area: BaseGeometry
    glass: bool = False


@dataclass
class FloorPlan:
    storey: str
    cut_height: float
    obstacles: list[ObstacleShape]
    outline: BaseGeometry  # building footprint (holes filled)
    solid: BaseGeometry  # union of obstacle footprints
    walls: list[WallSegment] = field(default_factory=list)

    @property
    def free(self) -> BaseGeometry:
        return self.outline.difference(self.solid)

    def obstacle_records(self) -> list[Obstacle]:
        records = []
        for shape in self.obstacles:
            for poly in polygons_of(shape.area):
                records.append(
                    Obstacle(
                        self.storey,
                        shape.element,
                        shape.ifc_class,
                        tuple(poly.exterior.coords),
                        tuple(tuple(r.coords) for r in poly.interiors),
                        shape.glass,
                    )
                )
        return records


def fill_holes(geometry: BaseGeometry) -> BaseGeometry:
    return shapely.union_all([Polygon(p.exterior) for p in polygons_of(geometry)])


def building_outline(solid: BaseGeometry, extra: list[BaseGeometry]) -> BaseGeometry:
    """The footprint of the building: obstacles and spaces, small gaps closed, holes filled."""
    parts = [solid, *extra]
    merged = shapely.union_all([p for p in parts if p is not None and not p.is_empty])
    if merged.is_empty:
        return merged
    closed = merged.buffer(_CLOSING, join_style="mitre").buffer(-_CLOSING, join_style="mitre")
    return fill_holes(closed.union(merged))


def _ring_edges(ring: LinearRing) -> np.ndarray:
    coords = np.asarray(ring.coords)[:, :2]
    return np.stack([coords[:-1], coords[1:]], axis=1)


def wall_surfaces(storey: str, obstacles: list[ObstacleShape], solid: BaseGeometry) -> list[WallSegment]:
    """Straight boundary pieces of ``solid`` with free-space normals and their source element."""
    if not obstacles or solid.is_empty:
        return []
    tree = shapely.STRtree([o.area for o in obstacles])
    segments: list[WallSegment] = []
    for poly in polygons_of(solid):
        poly = orient(poly, sign=1.0)  # exterior CCW, holes CW: solid is on the left of travel
        for ring in [poly.exterior, *poly.interiors]:
            edges = _ring_edges(ring)
            if len(edges) == 0:
                continue
            mids = shapely.points(edges.mean(axis=1))
            owners = tree.nearest(mids)
            segments.extend(_merge_edges(storey, edges, owners, obstacles))
    return segments


def _merge_edges(
    storey: str, edges: np.ndarray, owners: np.ndarray, obstacles: list[ObstacleShape]
) -> list[WallSegment]:
    merged: list[WallSegment] = []
    start = edges[0, 0]
    end = edges[0, 1]
    owner = owners[0]
    for (a, b), who in zip(edges[1:], owners[1:], strict=True):
        d_prev = end - start
        d_next = b - a
        angle = abs(math.atan2(d_prev[0] * d_next[1] - d_prev[1] * d_next[0], float(d_prev @ d_next)))
        if who == owner and angle < _COLLINEAR:
            end = b
            continue
        merged.append(_segment(storey, start, end, obstacles[owner]))
        start, end, owner = a, b, who
    merged.append(_segment(storey, start, end, obstacles[owner]))
    # A ring starts at an arbitrary vertex: join the last piece into the first if they continue.
    if len(merged) > 1:
        first, last = merged[0], merged[-1]
        if first.element == last.element and _same_direction(last, first):
            merged[0] = WallSegment(
                storey,
                first.element,
                first.ifc_class,
                last.x1,
                last.y1,
                first.x2,
                first.y2,
                first.normal,
                first.glass,
            )
            merged.pop()
    return [m for m in merged if m.length > 1e-3]


def _same_direction(a: WallSegment, b: WallSegment) -> bool:
    return (
        abs(
            math.atan2(
                a.normal[0] * b.normal[1] - a.normal[1] * b.normal[0],
                a.normal[0] * b.normal[0] + a.normal[1] * b.normal[1],
            )
        )
        < _COLLINEAR
    )


def _segment(storey: str, start: np.ndarray, end: np.ndarray, owner: ObstacleShape) -> WallSegment:
    dx, dy = float(end[0] - start[0]), float(end[1] - start[1])
    length = math.hypot(dx, dy) or 1.0
    normal = (dy / length, -dx / length)  # right of travel = away from the solid
    return WallSegment(
        storey,
        owner.element,
        owner.ifc_class,
        float(start[0]),
        float(start[1]),
        float(end[0]),
        float(end[1]),
        normal,
        owner.glass,
    )


def build_floorplan(
    storey: str, cut_height: float, obstacles: list[ObstacleShape], spaces: list[BaseGeometry]
) -> FloorPlan:
    solid = shapely.union_all([o.area for o in obstacles]) if obstacles else Polygon()
    # Remove zero-width slits and spikes where touching elements meet, keep corners sharp.
    solid = (
        solid.buffer(-_SLIVER, join_style="mitre").buffer(_SLIVER, join_style="mitre").simplify(_SLIVER / 2)
    )
    outline = building_outline(solid, spaces)
    plan = FloorPlan(storey, cut_height, obstacles, outline, solid)
    plan.walls = wall_surfaces(storey, obstacles, solid)
    return plan
