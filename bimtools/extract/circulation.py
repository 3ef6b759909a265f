"""Which side of a door is the circulation area (corridor, lobby) a robot drives in.

Decided, in this order (documented in the README):

1. IfcSpace adjacency: probe points just beyond each face; if exactly one side lies in a space
   whose name marks circulation (``circulation_spaces`` in the categories file), or the other
   side lies in a lift/stair space, that side wins.
2. Free-space test: the storey's free space (closed doors are obstacles) splits into regions;
   the side whose region borders more doors wins (corridors serve many doors, rooms one or
   two), then the larger region; a side outside the building or in a wall loses.
3. The door's placement +Y axis (the IFC opening direction).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from bimtools.site.records import FREE, OccupancyGrid

PROBE_DISTANCES = (0.35, 0.6, 0.9, 1.3)  # metres beyond the element's face


@dataclass
class SpaceIndex:
    """IfcSpace footprints of one storey, for name look-ups at a point."""

    names: list[str]
    areas: list[BaseGeometry]
    tree: shapely.STRtree | None = None

    def __post_init__(self) -> None:
        self.tree = shapely.STRtree(self.areas) if self.areas else None

    def name_at(self, x: float, y: float) -> str:
        if self.tree is None:
            return ""
        hits = self.tree.query(shapely.Point(x, y), predicate="intersects")
        if len(hits) == 0:
            return ""
        # The smallest space containing the point is the most specific.
        best = min(hits, key=lambda i: self.areas[i].area)
        return self.names[best]


@dataclass
class FreeRegions:
    """Connected regions of free space of a storey grid (4-connected)."""

    grid: OccupancyGrid
    labels: np.ndarray = field(init=False)
    areas: np.ndarray = field(init=False)  # m^2 per label, label 0 = not free
    doors: np.ndarray = field(init=False)  # doors bordering each region

    def __post_init__(self) -> None:
        free = (self.grid.cells == FREE).astype(np.uint8)
        count, labels, stats, _ = cv2.connectedComponentsWithStats(free, connectivity=4)
        self.labels = labels
        self.areas = stats[:, cv2.CC_STAT_AREA].astype(float) * self.grid.resolution**2
        self.areas[0] = 0.0
        self.doors = np.zeros(count, dtype=int)

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


def probe_side(
    regions: FreeRegions, spaces: SpaceIndex, point: np.ndarray, direction: np.ndarray
) -> SideProbe:
    """The free region and the space just off ``point`` (x, y) in ``direction``."""
    label, px, py = regions.probe(point[0], point[1], direction)
    return SideProbe(label, spaces.name_at(px, py), (px, py))


def choose_side(
    plus: SideProbe,
    minus: SideProbe,
    regions: FreeRegions,
    is_circulation: Callable[[str], bool],
    is_enclosure_space: Callable[[str], bool],
) -> tuple[int, str]:
    """+1 if the +direction side is the circulation side, -1 if the other; and the rule used."""
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
