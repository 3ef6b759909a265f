"""Small plan worlds for the lidar landmark tests, on both sides: the wall surfaces bim-extract
computes from them (:func:`bimtools.extract.floorplan.build_floorplan`), the segments a simulated
lidar ray-casts against, and noisy scans (2 cm range noise, 1 % dropouts by default)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Point, Polygon, box
from shapely.geometry.base import BaseGeometry

from bimtools.extract.floorplan import FloorPlan, ObstacleShape, build_floorplan
from bimtools.extract.landmarks import wall_landmarks
from bimtools.extract.section import polygons_of
from bimtools.settings import LandmarkSettings
from initcli.core.geometry.raycast import cast_rays

WALL = 0.2  # m: wall thickness of the worlds
BEAMS = 360
RANGE_MAX = 20.0
SETTINGS = LandmarkSettings(enabled=True)


@dataclass
class World:
    """Free space (the rooms) and solid (walls, columns, leaves) of a storey."""

    rooms: BaseGeometry
    solid: BaseGeometry

    @property
    def plan(self) -> FloorPlan:
        shapes = [ObstacleShape(f"wall{i}", "IfcWall", p) for i, p in enumerate(polygons_of(self.solid))]
        return build_floorplan("L", 1.0, shapes, [self.rooms])

    @property
    def segments(self) -> np.ndarray:
        """(S, 4) edges of the solid's outlines, for ray casting."""
        parts = []
        for poly in polygons_of(self.solid):
            for ring in [poly.exterior, *poly.interiors]:
                c = np.asarray(ring.coords)[:, :2]
                parts.append(np.column_stack([c[:-1], c[1:]]))
        return np.concatenate(parts)

    def free(self, x: float, y: float) -> bool:
        p = Point(x, y)
        return bool(self.rooms.contains(p) and not self.solid.contains(p))

    def truth(self, settings: LandmarkSettings = SETTINGS):
        """The landmarks bim-extract's rules find in this world (seen from the rooms)."""
        return wall_landmarks(self.plan.walls, settings, self.free)

    def scan(
        self,
        x: float,
        y: float,
        yaw: float = 0.0,
        rng: np.random.Generator | None = None,
        noise: float = 0.02,
        dropout: float = 0.01,
    ) -> tuple[np.ndarray, float, float]:
        """(ranges, angle_min, angle_increment) of a full-turn scan from pose (x, y, yaw)."""
        inc = 2 * math.pi / BEAMS
        a0 = -math.pi
        angles = a0 + inc * np.arange(BEAMS) + yaw
        r = cast_rays(np.array([x, y]), angles, self.segments, RANGE_MAX)
        if rng is not None:
            hit = r < RANGE_MAX
            r = np.where(hit, np.clip(r + rng.normal(0.0, noise, BEAMS), 0.06, RANGE_MAX - 1e-3), r)
            r[rng.random(BEAMS) < dropout] = RANGE_MAX
        return r, a0, inc


def walled(rooms: BaseGeometry, extra: list[BaseGeometry] = (), openings: list[BaseGeometry] = ()) -> World:
    """Rooms with walls WALL thick all round, ``openings`` cut through them, ``extra`` solids added."""
    ring = rooms.buffer(WALL, join_style="mitre").difference(rooms)
    for cut in openings:
        ring = ring.difference(cut)
    solid = shapely.union_all([ring, *extra])
    return World(rooms, solid)


def l_room() -> World:
    return walled(Polygon([(0, 0), (8, 0), (8, 4), (4, 4), (4, 8), (0, 8)]))


def corridor_with_door(leaf_recess: float | None = None, gap: float = 0.9) -> World:
    """A corridor (12 x 2 m) and a room north of it through a door ``gap`` wide at x = 6: open
    (None) or closed by a 4 cm leaf set ``leaf_recess`` back from the corridor's wall face."""
    corridor, room = box(0, 0, 12, 2), box(4, 2 + WALL, 8, 6)
    doorway = box(6 - gap / 2, 2 - 0.01, 6 + gap / 2, 2 + WALL + 0.01)
    leaf = (
        []
        if leaf_recess is None
        else [box(6 - gap / 2, 2 + leaf_recess, 6 + gap / 2, 2 + leaf_recess + 0.04)]
    )
    world = walled(shapely.union_all([corridor, room, doorway]), extra=leaf)
    return world


def room_with(*things: BaseGeometry, size: tuple[float, float] = (8.0, 6.0)) -> World:
    """A rectangular room holding free-standing solids (columns, boxes)."""
    return walled(box(0, 0, *size), extra=list(things))


__all__ = [
    "BEAMS",
    "RANGE_MAX",
    "SETTINGS",
    "WALL",
    "World",
    "corridor_with_door",
    "l_room",
    "room_with",
    "walled",
]
