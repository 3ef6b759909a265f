"""Typed records of the site model (paper Table 1 features, wall surfaces, obstacles)."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "BUILTIN_CATEGORIES",
    "EXTRA_COLUMNS",
    "FEATURE_COLUMNS",
    "FREE",
    "Feature",
    "OCCUPIED",
    "Obstacle",
    "OccupancyGrid",
    "StoreyInfo",
    "TABLE1_COLUMNS",
    "UNKNOWN",
    "WallSegment",
]

# The first eight columns of features.csv are exactly the paper's Table 1.
TABLE1_COLUMNS = ("ID", "Category", "X", "Y", "Norm_X", "Norm_Y", "Width", "Height")
EXTRA_COLUMNS = ("Storey", "Elevation", "IfcClass", "Name")
FEATURE_COLUMNS = TABLE1_COLUMNS + EXTRA_COLUMNS

BUILTIN_CATEGORIES = ("Door", "Lift", "Stairs")

# Which sensor sees a feature: the one place that says it. Camera features are the categories of the
# categories file (Door, Lift, Stairs or a user's own); lidar landmarks are the wall geometry that
# bim-extract adds with the categories file's ``landmarks:`` block (bimtools.extract.landmarks):
#   ConcaveCorner  an inner corner of a room (the two faces meet at 60-120 degrees seen from inside)
#   ConvexCorner   an outer corner (a wall end, a pillar or shaft corner standing into the room)
#   ColumnCorner   an outer corner of a free-standing column (a small closed outline)
#   Opening        a gap of door width in a wall line, with wall on both sides (a doorway, or the
#                  recess of a door leaf set back in its frame)
CAMERA = "camera"
LIDAR = "lidar"
SENSORS = (CAMERA, LIDAR)
LANDMARK_CATEGORIES = ("ConcaveCorner", "ConvexCorner", "ColumnCorner", "Opening")


def sensor_of(category: str) -> str:
    """``"lidar"`` for a landmark category, ``"camera"`` for every other (a category of the file)."""
    return LIDAR if category in LANDMARK_CATEGORIES else CAMERA


@dataclass(frozen=True)
class Feature:
    """One BIM feature b_u (Eq. 4): a door, lift or staircase entrance seen from circulation.

    ``x, y`` is the centre of the element's face at floor level in the world XY frame (metres);
    ``norm_x, norm_y`` the unit normal pointing to the side a robot sees it from.
    """

    id: str
    category: str
    x: float
    y: float
    norm_x: float
    norm_y: float
    width: float
    height: float
    storey: str = ""
    elevation: float = 0.0
    ifc_class: str = ""
    name: str = ""

    @property
    def heading(self) -> float:
        """Direction of the normal in radians."""
        return math.atan2(self.norm_y, self.norm_x)

    @property
    def sensor(self) -> str:
        """Which sensor sees it: ``"camera"`` (doors, lifts, stairs) or ``"lidar"`` (a landmark)."""
        return sensor_of(self.category)


def camera_features(features: Iterable[Feature]) -> list[Feature]:
    """The features a camera detector sees (every row that is not a lidar landmark)."""
    return [f for f in features if f.sensor == CAMERA]


def lidar_landmarks(features: Iterable[Feature]) -> list[Feature]:
    """The wall corners, column corners and openings (rows of the LANDMARK_CATEGORIES)."""
    return [f for f in features if f.sensor == LIDAR]


@dataclass(frozen=True)
class WallSegment:
    """A straight piece of wall surface cut at the section height (used by Eq. 17).

    ``normal`` is the unit vector pointing from the wall into free space.
    """

    storey: str
    element: str
    ifc_class: str
    x1: float
    y1: float
    x2: float
    y2: float
    normal: tuple[float, float]
    glass: bool = False  # the surface of a glazed element (window, curtain wall, panel)

    @property
    def length(self) -> float:
        return math.hypot(self.x2 - self.x1, self.y2 - self.y1)


@dataclass(frozen=True)
class Obstacle:
    """The footprint of a solid element at the section height (wall, column, closed door...)."""

    storey: str
    element: str
    ifc_class: str
    exterior: tuple[tuple[float, float], ...]
    holes: tuple[tuple[tuple[float, float], ...], ...] = ()
    glass: bool = False  # a glazed element: blocks motion, mostly transparent to a lidar


@dataclass
class StoreyInfo:
    """What the manifest says of one storey."""

    name: str
    elevation: float
    counts: dict[str, int] = field(default_factory=dict)
    map_yaml: str | None = None
    preview: str | None = None


# Occupancy grid pixel values (ROS map_server / Nav2 trinary): written by bimtools.site.occupancy_map.
FREE = 254
OCCUPIED = 0
UNKNOWN = 205


@dataclass
class OccupancyGrid:
    """A trinary occupancy grid; ``cells[0]`` is the top row (largest y)."""

    cells: np.ndarray  # uint8, shape (rows, cols)
    resolution: float
    origin: tuple[float, float, float]
    negate: int = 0
    occupied_thresh: float = 0.65
    # 0.196, not 0.25: with 0.25 the unknown value 205 ((255-205)/255 = 0.196) would load as free.
    free_thresh: float = 0.196

    @property
    def shape(self) -> tuple[int, int]:
        return self.cells.shape

    def content_key(self) -> tuple[object, ...]:
        """What the map holds, as a hashable key (cells by a hash of their bytes): two grids with
        the same key are the same map, whichever objects hold them."""
        cells = np.ascontiguousarray(self.cells)
        return (cells.shape, cells.dtype.str, hash(cells.tobytes()), self.resolution, tuple(self.origin))

    def world_to_cell(self, x: np.ndarray | float, y: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """World coordinates -> (row, col) integer indices (may be out of bounds)."""
        col = np.floor((np.asarray(x) - self.origin[0]) / self.resolution).astype(int)
        row_from_bottom = np.floor((np.asarray(y) - self.origin[1]) / self.resolution).astype(int)
        return self.cells.shape[0] - 1 - row_from_bottom, col

    def cell_centre(self, row: np.ndarray | int, col: np.ndarray | int) -> tuple[np.ndarray, np.ndarray]:
        x = self.origin[0] + (np.asarray(col) + 0.5) * self.resolution
        y = self.origin[1] + (self.cells.shape[0] - 1 - np.asarray(row) + 0.5) * self.resolution
        return x, y

    def value_at(self, x: float, y: float) -> int:
        """Pixel value at a world point; UNKNOWN outside the grid."""
        row, col = self.world_to_cell(x, y)
        if 0 <= row < self.cells.shape[0] and 0 <= col < self.cells.shape[1]:
            return int(self.cells[row, col])
        return UNKNOWN

    def occupancy(self) -> np.ndarray:
        """Per-cell state as map_server reads it: 1 occupied, 0 free, -1 unknown."""
        p = self.cells.astype(float) / 255.0 if self.negate else (255.0 - self.cells.astype(float)) / 255.0
        state = np.full(self.cells.shape, -1, dtype=np.int8)
        state[p > self.occupied_thresh] = 1
        state[p < self.free_thresh] = 0
        return state
