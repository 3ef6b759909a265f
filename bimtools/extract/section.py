"""Horizontal sections of triangle meshes: the footprint of a solid at a given height."""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.base import BaseGeometry

__all__ = ["GLASS_MAX_DEPTH", "polygons_of", "projected_footprint", "section_polygon", "section_segments"]

_SNAP = 1e-5  # metres; intersection points are rounded to this grid so loops close


def section_segments(verts: np.ndarray, faces: np.ndarray, z: float) -> np.ndarray:
    """Segments (k, 2, 2) where the plane ``z`` cuts the triangles of a mesh.

    Each crossing triangle contributes the two points where its edges cross the plane. The same
    edge always gives the same point (edges are ordered by vertex index), so loops close exactly.
    """
    z = float(z) + 1e-7  # avoid vertices lying exactly on the plane
    tri_z = verts[faces, 2]
    crossing = (tri_z.min(axis=1) < z) & (tri_z.max(axis=1) > z)
    if not crossing.any():
        return np.empty((0, 2, 2))
    tris = faces[crossing]
    points = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        lo = np.minimum(tris[:, a], tris[:, b])
        hi = np.maximum(tris[:, a], tris[:, b])
        z_lo, z_hi = verts[lo, 2], verts[hi, 2]
        cuts = (z_lo - z) * (z_hi - z) < 0
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(cuts, (z - z_lo) / (z_hi - z_lo), np.nan)
        p = verts[lo, :2] + s[:, None] * (verts[hi, :2] - verts[lo, :2])
        points.append(p)
    stacked = np.stack(points, axis=1)  # (k, 3 edges, 2)
    valid = ~np.isnan(stacked[:, :, 0])
    keep = valid.sum(axis=1) == 2
    stacked, valid = stacked[keep], valid[keep]
    order = np.argsort(~valid, axis=1, kind="stable")[:, :2]
    segments = np.take_along_axis(stacked, order[:, :, None], axis=1)
    return np.round(segments / _SNAP) * _SNAP


def section_polygon(verts: np.ndarray, faces: np.ndarray, z: float) -> BaseGeometry | None:
    """The area a closed mesh covers in the plane ``z`` (Polygon/MultiPolygon), or None.

    Closed loops are polygonised and combined even-odd, so holes come out as holes. An open or
    broken mesh falls back to a thin buffer around its cut lines.
    """
    segments = section_segments(verts, faces, z)
    if len(segments) == 0:
        return None
    lines = shapely.linestrings(segments)
    faces_2d = shapely.get_parts(shapely.polygonize(lines))
    area: BaseGeometry | None = None
    for face in faces_2d:
        ring = Polygon(face.exterior)
        if ring.area < 1e-8:
            continue
        area = ring if area is None else area.symmetric_difference(ring)
    if area is None or area.is_empty:
        area = shapely.union_all(lines).buffer(0.01)
    area = area.buffer(0)
    if area.is_empty:
        return None
    return area


def polygons_of(geometry: BaseGeometry | None) -> list[Polygon]:
    """The polygons of a geometry (empty for None, points and lines)."""
    if geometry is None or geometry.is_empty:
        return []
    if isinstance(geometry, Polygon):
        return [geometry]
    if isinstance(geometry, MultiPolygon):
        return list(geometry.geoms)
    return [g for g in shapely.get_parts(geometry) if isinstance(g, Polygon)]


GLASS_MAX_DEPTH = 0.6  # metres: a glazed element thicker than this in plan is not projected whole
_PANE = 0.01  # metres: half the thickness given to a glass pane modelled as a bare surface


def projected_footprint(
    verts: np.ndarray, z_lo: float, z_hi: float, max_depth: float = GLASS_MAX_DEPTH
) -> BaseGeometry | None:
    """The plan footprint of a thin element (window, glass panel) over a height band.

    A section through a window or curtain-wall panel at the cut height often meets only a few
    frame pieces (the glass is thin or left out of the body), which leaves the facade open. The
    element's whole body projected to the plan closes it: the convex hull of its vertices within
    ``[z_lo, z_hi]`` (all vertices when fewer than three lie there). Returns None when that hull
    is more than ``max_depth`` across (a curved or deep element: not thin, so not projected).
    """
    band = verts[(verts[:, 2] >= z_lo) & (verts[:, 2] <= z_hi)]
    points = band[:, :2] if len(band) >= 3 else verts[:, :2]
    if len(points) < 2:
        return None
    hull = shapely.convex_hull(shapely.multipoints(points))
    if hull.geom_type == "LineString":
        return hull.buffer(_PANE, cap_style="flat") if hull.length > 1e-3 else None
    if hull.geom_type != "Polygon" or hull.area < 1e-8:
        return None
    rect = shapely.minimum_rotated_rectangle(hull)
    edges = np.diff(np.asarray(rect.exterior.coords)[:, :2], axis=0)
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    if float(lengths.min()) > max_depth:
        return None
    return hull
