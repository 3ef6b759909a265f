"""Which side of a door is the circulation area (corridor, lobby) a robot drives in.

Geometry first, names second. Probe points just beyond each face; then, in this order
(documented in docs/extract.md):

1. Reachable: a side outside the building (no free space and no space there) loses.
2. Plan shape: each side's place (the IfcSpace the probe lies in, else its free-space region)
   is circulation when it is long and narrow and serves several doors, or serves several doors
   and leads to a staircase or lift (:func:`is_circulation_shape`). If exactly one side is, it
   wins.
3. Names: if exactly one side lies in a space whose name marks circulation
   (``circulation_spaces`` in the categories file), or the other side lies in a lift/stair
   space, that side wins.
4. Free-space test: the storey's free space (closed doors are obstacles) splits into regions;
   the side whose region borders more doors wins (corridors serve many doors, rooms one or
   two), then the larger region.
5. The door's placement +Y axis (the IFC opening direction).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from bimtools.site.records import FREE, OccupancyGrid

__all__ = [
    "CORRIDOR_MAX_WIDTH",
    "CORRIDOR_MIN_DOORS",
    "CORRIDOR_MIN_ELONGATION",
    "FreeRegions",
    "PROBE_DISTANCES",
    "PlaceShape",
    "SideProbe",
    "SpaceIndex",
    "choose_side",
    "is_circulation_shape",
    "is_plan_circulation",
    "place_shape",
    "probe_side",
    "rectangle_equivalent",
]

PROBE_DISTANCES = (0.35, 0.6, 0.9, 1.3)  # metres beyond the element's face
CORRIDOR_MAX_WIDTH = 3.5  # metres: a corridor is at most this wide ...
CORRIDOR_MIN_ELONGATION = 3.0  # ... and at least this many times longer than wide
CORRIDOR_MIN_DOORS = 3  # doors a circulation place serves (a room has one or two)


@dataclass(frozen=True)
class PlaceShape:
    """What the plan says of a place (a space or a free region): size, doors, vertical links."""

    width: float  # metres
    length: float  # metres
    doors: int
    vertical: bool  # a door or a body links it to a staircase or lift


def is_circulation_shape(place: PlaceShape) -> bool:
    """Circulation by geometry: a long narrow place serving several doors (a corridor), or one
    serving several doors and leading to a staircase or lift (a hall, a landing)."""
    narrow = 0.0 < place.width <= CORRIDOR_MAX_WIDTH and place.length >= CORRIDOR_MIN_ELONGATION * place.width
    if place.doors >= CORRIDOR_MIN_DOORS and (narrow or place.vertical):
        return True
    return narrow and place.vertical and place.doors >= 2


def rectangle_equivalent(area: float, perimeter: float) -> tuple[float, float]:
    """(length, width) of the rectangle with the same area and perimeter (a square when none)."""
    half = perimeter / 2.0
    disc = half * half - 4.0 * area
    if area <= 0.0:
        return 0.0, 0.0
    if disc <= 0.0:
        side = float(np.sqrt(area))
        return side, side
    width = (half - float(np.sqrt(disc))) / 2.0
    return area / width, width


@dataclass
class SpaceIndex:
    """IfcSpace footprints of one storey, for name look-ups at a point."""

    names: list[str]
    areas: list[BaseGeometry]
    tree: shapely.STRtree | None = None
    doors: np.ndarray = field(init=False)  # doors whose probe lies in each space
    vertical: np.ndarray = field(init=False)  # space linked to a staircase or lift

    def __post_init__(self) -> None:
        self.tree = shapely.STRtree(self.areas) if self.areas else None
        self.doors = np.zeros(len(self.areas), dtype=int)
        self.vertical = np.zeros(len(self.areas), dtype=bool)

    def index_at(self, x: float, y: float) -> int:
        """The smallest space containing (x, y) (the most specific), or -1."""
        if self.tree is None:
            return -1
        hits = self.tree.query(shapely.Point(x, y), predicate="intersects")
        if len(hits) == 0:
            return -1
        return int(min(hits, key=lambda i: self.areas[i].area))

    def name_at(self, x: float, y: float) -> str:
        index = self.index_at(x, y)
        return self.names[index] if index >= 0 else ""

    def shape(self, index: int) -> PlaceShape:
        area = self.areas[index]
        length, width = rectangle_equivalent(float(area.area), float(area.length))
        return PlaceShape(width, length, int(self.doors[index]), bool(self.vertical[index]))


@dataclass
class FreeRegions:
    """Connected regions of free space of a storey grid (4-connected)."""

    grid: OccupancyGrid
    labels: np.ndarray = field(init=False)
    areas: np.ndarray = field(init=False)  # m^2 per label, label 0 = not free
    doors: np.ndarray = field(init=False)  # doors bordering each region
    widths: np.ndarray = field(init=False)  # metres: typical width of each region
    vertical: np.ndarray = field(init=False)  # region linked to a staircase or lift

    def __post_init__(self) -> None:
        free = (self.grid.cells == FREE).astype(np.uint8)
        count, labels, stats, _ = cv2.connectedComponentsWithStats(free, connectivity=4)
        self.labels = labels
        self.areas = stats[:, cv2.CC_STAT_AREA].astype(float) * self.grid.resolution**2
        self.areas[0] = 0.0
        self.doors = np.zeros(count, dtype=int)
        self.vertical = np.zeros(count, dtype=bool)
        # Width from the distance to the nearest non-free cell: its mean over a strip of width w
        # is w / 4 (a square of side a gives a / 6, so rooms come out wide, as they are).
        distance = cv2.distanceTransform(free, cv2.DIST_L2, 3) * self.grid.resolution
        cells = np.maximum(stats[:, cv2.CC_STAT_AREA], 1)
        self.widths = 4.0 * np.bincount(labels.ravel(), weights=distance.ravel(), minlength=count) / cells

    def shape(self, label: int) -> PlaceShape:
        width = float(self.widths[label])
        length = float(self.areas[label]) / width if width > 0 else 0.0
        return PlaceShape(width, length, int(self.doors[label]), bool(self.vertical[label]))

    def label_at(self, x: float, y: float) -> int:
        row, col = self.grid.world_to_cell(x, y)
        if 0 <= row < self.labels.shape[0] and 0 <= col < self.labels.shape[1]:
            return int(self.labels[row, col])
        return 0

    def labels_at(self, points: np.ndarray) -> set[int]:
        if len(points) == 0:
            return set()
        rows, cols = self.grid.world_to_cell(points[:, 0], points[:, 1])
        ok = (rows >= 0) & (rows < self.labels.shape[0]) & (cols >= 0) & (cols < self.labels.shape[1])
        found = set(np.unique(self.labels[rows[ok], cols[ok]]).tolist())
        found.discard(0)
        return found

    def probe(self, x: float, y: float, direction: np.ndarray) -> tuple[int, float, float]:
        """First free region beyond (x, y) along ``direction``: (label, px, py); label 0 if none."""
        for distance in PROBE_DISTANCES:
            px, py = x + direction[0] * distance, y + direction[1] * distance
            label = self.label_at(px, py)
            if label:
                return label, px, py
        px, py = x + direction[0] * PROBE_DISTANCES[1], y + direction[1] * PROBE_DISTANCES[1]
        return 0, px, py

    def score(self, label: int) -> tuple[int, float]:
        if label == 0:
            return (-1, 0.0)
        return (int(self.doors[label]), float(self.areas[label]))


@dataclass
class SideProbe:
    """What lies on one side of an element's face."""

    label: int
    space: str
    point: tuple[float, float]
    space_index: int = -1
    space_area: float = 0.0  # m^2 of the space there (0 when none)

    @property
    def reachable(self) -> bool:
        """Inside the building: free space or a space (not outside, not inside a wall)."""
        return self.label != 0 or self.space_index >= 0


def probe_side(
    regions: FreeRegions, spaces: SpaceIndex, x: float, y: float, direction: np.ndarray
) -> SideProbe:
    label, px, py = regions.probe(x, y, direction)
    index = spaces.index_at(px, py)
    if index < 0:
        return SideProbe(label, "", (px, py))
    return SideProbe(label, spaces.names[index], (px, py), index, float(spaces.areas[index].area))


def place_shape(side: SideProbe, regions: FreeRegions, spaces: SpaceIndex) -> PlaceShape | None:
    """The place a side opens into: its IfcSpace when there is one, else its free region."""
    if side.space_index >= 0:
        return spaces.shape(side.space_index)
    if side.label != 0:
        return regions.shape(side.label)
    return None


def is_plan_circulation(side: SideProbe, regions: FreeRegions, spaces: SpaceIndex) -> bool:
    place = place_shape(side, regions, spaces)
    return place is not None and is_circulation_shape(place)


def choose_side(
    plus: SideProbe,
    minus: SideProbe,
    regions: FreeRegions,
    is_circulation: Callable[[str], bool],
    is_enclosure_space: Callable[[str], bool],
    spaces: SpaceIndex | None = None,
) -> tuple[int, str]:
    """+1 if the +direction side is the circulation side, -1 if the other; and the rule used."""
    if plus.reachable != minus.reachable:
        return (1 if plus.reachable else -1), "outside"
    if spaces is not None:
        plan_plus = is_plan_circulation(plus, regions, spaces)
        plan_minus = is_plan_circulation(minus, regions, spaces)
        if plan_plus != plan_minus:
            return (1 if plan_plus else -1), "plan"
    circ_plus, circ_minus = is_circulation(plus.space), is_circulation(minus.space)
    if circ_plus != circ_minus:
        return (1 if circ_plus else -1), "space"
    encl_plus, encl_minus = is_enclosure_space(plus.space), is_enclosure_space(minus.space)
    if encl_plus != encl_minus:
        return (-1 if encl_plus else 1), "space"
    if plus.label != minus.label:
        s_plus, s_minus = regions.score(plus.label), regions.score(minus.label)
        if s_plus != s_minus:
            return (1 if s_plus > s_minus else -1), "free-space"
    if bool(plus.space) != bool(minus.space):
        return (1 if plus.space else -1), "space"
    return 1, "placement"
