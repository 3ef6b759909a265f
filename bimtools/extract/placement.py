"""Where a feature is: the face of a door-like element, the foot of a stair, the front of a shaft.

Pure geometry on numpy arrays and shapely shapes; no IFC access.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

__all__ = [
    "CLIMB_RISE",
    "DEEPER_THAN_WIDE",
    "Front",
    "MAX_FACE_OFFSET",
    "Opening",
    "heading_deg",
    "opening_in_plan",
    "rectangle_fronts",
    "stair_foot",
]

MAX_FACE_OFFSET = 0.25  # metres from the element's centre plane to the face used as X, Y
DEEPER_THAN_WIDE = 1.5  # a door this many times deeper than wide along its placement X is turned
CLIMB_RISE = 1.0  # metres of rise over which a stair's climb at its foot is measured


@dataclass(frozen=True)
class Opening:
    """A door-like element in plan: centre of its footprint, axis along the wall, the across axis."""

    centre: np.ndarray  # (2,) footprint centre
    along: np.ndarray  # unit, along the wall (width direction)
    across: np.ndarray  # unit, perpendicular; +placement Y (the IFC opening direction)
    width: float
    depth: float
    height: float
    floor_z: float

    def face(self, side: int) -> np.ndarray:
        """Centre of the face on the ``side`` (+1 along ``across``, -1 against) at floor level."""
        return self.centre + side * min(self.depth / 2.0, MAX_FACE_OFFSET) * self.across


def _unit(v: np.ndarray) -> np.ndarray | None:
    n = float(np.hypot(v[0], v[1]))
    return None if n < 1e-6 else np.asarray(v[:2], dtype=float) / n


def opening_in_plan(
    verts: np.ndarray, x_axis: np.ndarray, y_axis: np.ndarray, width: float | None, height: float | None
) -> Opening:
    """Footprint of a door-like element from its mesh and placement axes (world frame, metres).

    The local X axis of a door's placement runs along the wall; local Y across it. When X is not
    horizontal, or the element is plainly deeper than wide along it (a Vectorworks export keeps
    the identity placement and puts the shape in world coordinates, so X may run across the
    wall), the footprint's long side is used instead.
    """
    along = _unit(x_axis)
    if along is None or _across_the_wall(verts, along, width):
        along = _long_side(verts)
    across = np.array([-along[1], along[0]])
    y = _unit(y_axis)
    if y is not None and float(across @ y) < 0:
        across = -across
    s = verts[:, :2] @ along
    t = verts[:, :2] @ across
    centre = along * (s.min() + s.max()) / 2.0 + across * (t.min() + t.max()) / 2.0
    z0, z1 = float(verts[:, 2].min()), float(verts[:, 2].max())
    return Opening(
        centre=centre,
        along=along,
        across=across,
        width=float(width) if width else float(s.max() - s.min()),
        depth=float(t.max() - t.min()),
        height=float(height) if height else z1 - z0,
        floor_z=z0,
    )


def _long_side(verts: np.ndarray) -> np.ndarray:
    """Unit direction of the long side of the footprint's minimum rotated rectangle."""
    rect = shapely.minimum_rotated_rectangle(shapely.multipoints(verts[:, :2]))
    coords = np.asarray(rect.exterior.coords if rect.geom_type == "Polygon" else rect.coords)
    edges = np.diff(coords[:, :2], axis=0)
    along = _unit(edges[int(np.argmax(np.hypot(edges[:, 0], edges[:, 1])))]) if len(edges) else None
    return np.array([1.0, 0.0]) if along is None else along


def _across_the_wall(verts: np.ndarray, along: np.ndarray, width: float | None) -> bool:
    """Does ``along`` (the placement's X) run across the wall? The element is more than
    ``DEEPER_THAN_WIDE`` times as deep as wide along it, and its depth is nearer its nominal
    ``width`` (when known) than its width is. A door drawn open stands about as deep as wide and
    keeps its placement."""
    s = verts[:, :2] @ along
    t = verts[:, :2] @ np.array([-along[1], along[0]])
    wide, deep = float(s.max() - s.min()), float(t.max() - t.min())
    if deep <= DEEPER_THAN_WIDE * wide:
        return False
    return width is None or abs(deep - width) < abs(wide - width)


@dataclass(frozen=True)
class Front:
    """A feature position and the direction it is seen from."""

    point: np.ndarray
    normal: np.ndarray
    width: float
    height: float


def stair_foot(parts: list[np.ndarray]) -> Front | None:
    """The foot of a staircase (Stairs fallback when it has no enclosure door).

    ``parts`` are the vertex arrays of the stair's flights (or the stair itself). The lowest
    flight gives the climbing direction (centroid of its low vertices -> centroid of those
    ``CLIMB_RISE`` higher, or of its top when it rises less: a stair exported as one body that
    turns, U-shaped or three-quarter, climbs elsewhere at its top than at its foot); the foot is
    the edge of its lowest vertices, seen from the side the climb starts.
    """
    parts = [p for p in parts if len(p)]
    if not parts:
        return None
    lowest = min(parts, key=lambda p: float(p[:, 2].min()))
    z0, z1 = float(lowest[:, 2].min()), float(lowest[:, 2].max())
    band = max(0.05, min(0.35, (z1 - z0) / 4.0))
    top = min(z1, z0 + CLIMB_RISE)
    low = lowest[lowest[:, 2] <= z0 + band, :2]
    high = lowest[(lowest[:, 2] >= top - band) & (lowest[:, 2] <= top), :2]
    if not len(high):  # a coarse body with no vertex near that height: its top
        high = lowest[lowest[:, 2] >= z1 - band, :2]
    climb = _unit(high.mean(axis=0) - low.mean(axis=0))
    if climb is None:
        return None
    side = np.array([-climb[1], climb[0]])
    s = low @ climb
    u = low @ side
    point = climb * float(s.min()) + side * float((u.min() + u.max()) / 2.0)
    return Front(point=point, normal=-climb, width=float(u.max() - u.min()), height=z1 - z0)


def rectangle_fronts(footprint: BaseGeometry) -> list[Front]:
    """The four sides of a footprint's minimum rotated rectangle, each with its outward normal."""
    rect = shapely.minimum_rotated_rectangle(footprint)
    if rect.geom_type != "Polygon":
        return []
    rect = shapely.geometry.polygon.orient(rect, sign=1.0)
    coords = np.asarray(rect.exterior.coords)[:, :2]
    fronts = []
    for a, b in zip(coords[:-1], coords[1:], strict=True):
        d = _unit(b - a)
        if d is None:
            continue
        normal = np.array([d[1], -d[0]])  # right of a CCW ring = outward
        fronts.append(Front(point=(a + b) / 2.0, normal=normal, width=float(np.hypot(*(b - a))), height=2.1))
    return fronts


def heading_deg(v: np.ndarray) -> float:
    return math.degrees(math.atan2(v[1], v[0]))
