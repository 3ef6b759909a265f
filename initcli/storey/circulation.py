"""The circulation area of a storey: the free cells of its map that camera features face, with every
obstacle the world adds (closed door leaves, hoardings, material stacks) burnt in first."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import StoreyModel
from bimtools.site.records import FREE, Obstacle, OccupancyGrid

__all__ = ["Circulation", "NoFreeSpace"]


class NoFreeSpace(InputError, ValueError):
    """A storey whose map holds no free space a robot can stand on: bad input for a session (one
    line, exit 2), a storey the survey skips."""


@dataclass
class Circulation:
    """Free cells of the connected region that most camera features face (corridors, lobbies)."""

    grid: OccupancyGrid
    label: np.ndarray  # bool mask of the region
    clearance: np.ndarray  # metres to the nearest non-free cell
    regions: np.ndarray | None = None  # connected free regions (0: not free), as the world has them

    def region_at(self, x: float, y: float) -> int:
        """The free region holding a world point (0: not free or outside the map)."""
        if self.regions is None:
            return 0
        row, col = self.grid.world_to_cell(x, y)
        if not (0 <= row < self.regions.shape[0] and 0 <= col < self.regions.shape[1]):
            return 0
        return int(self.regions[row, col])

    @staticmethod
    def of(
        storey: StoreyModel,
        closed: Sequence[Obstacle] = (),
        boxes: Sequence[np.ndarray] = (),
        footprint: float = 0.0,
        min_votes: int = 0,
    ) -> Circulation:
        """The region of the storey map that most camera features (doors, lifts, stairs; a lidar
        landmark faces rooms as often as corridors) face. ``closed``: obstacles of the simulated
        world that the map leaves open (closed door leaves, hoardings) and ``boxes``: closed (n, 2)
        rings of material stacks, burnt in first; ``footprint``: the robot's radius (m), by which the
        free space is shrunk before it is split into connected regions. The region is then the one a
        robot of that size can actually drive in: rooms behind closed doors, corridor sections closed
        off by hoardings and gaps narrower than the robot are not part of it. ``clearance`` stays the
        distance to the nearest obstacle. ``min_votes`` > 0: the region is every connected region
        that at least that many features face (all corridor sections between closed doors), not
        only the one most face."""
        grid = storey.grid
        if grid is None:
            raise NoFreeSpace(f"storey {storey.name!r} has no occupancy map")
        free = (grid.cells == FREE).astype(np.uint8)
        rings = [np.asarray(o.exterior, dtype=float).reshape(-1, 2) for o in closed]
        rings += [np.asarray(b, dtype=float).reshape(-1, 2) for b in boxes]
        for ring in rings:
            if len(ring) < 3:
                continue
            row, col = grid.world_to_cell(ring[:, 0], ring[:, 1])
            pts = np.column_stack([col, row]).astype(np.int32)
            cv2.fillPoly(free, [pts], 0)
            cv2.polylines(free, [pts], True, 0, thickness=1)
        clearance = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * grid.resolution
        passable = free if footprint <= 0 else (clearance >= footprint).astype(np.uint8)
        _, labels = cv2.connectedComponents(passable, connectivity=4)
        votes: dict[int, int] = {}
        for f in storey.camera_features:  # doors, lifts, stairs: a wall corner faces rooms too
            for out in (0.6, 0.9, 1.2):  # m in front of the feature: the first passable cell votes
                row, col = grid.world_to_cell(f.x + out * f.norm_x, f.y + out * f.norm_y)
                if 0 <= row < labels.shape[0] and 0 <= col < labels.shape[1] and labels[row, col]:
                    votes[int(labels[row, col])] = votes.get(int(labels[row, col]), 0) + 1
                    break
        sizes = np.bincount(labels.ravel())[1:]
        if not votes and not len(sizes):
            wide = f" a robot of radius {footprint:g} m can stand on" if footprint > 0 else ""
            raise NoFreeSpace(
                f"storey {storey.name!r}: its map has no free space{wide} (an open building without "
                "spaces or floor slabs leaves its free space outside the footprint: bim-extract bounds "
                "it by walls, IfcSpace and IfcSlab)"
            )
        main = max(votes, key=lambda label: votes[label]) if votes else int(sizes.argmax() + 1)
        faced = [label for label, n in votes.items() if n >= min_votes] if min_votes > 0 else []
        region = np.isin(labels, faced) if faced else labels == main
        return Circulation(grid, region, clearance, labels)

    def cells(self, min_clearance: float) -> np.ndarray:
        rows, cols = np.nonzero(self.label & (self.clearance >= min_clearance))
        x, y = self.grid.cell_centre(rows, cols)
        return np.column_stack([x, y])

    def reaches(self, x: float, y: float, within: float) -> bool:
        """Whether a cell of the region lies within ``within`` metres of a point (a robot standing
        closer to a wall than the region's footprint allows can still drive into it)."""
        row, col = self.grid.world_to_cell(x, y)
        k = max(0, int(math.ceil(within / self.grid.resolution)))
        r0, c0 = max(0, int(row) - k), max(0, int(col) - k)
        patch = self.label[r0 : int(row) + k + 1, c0 : int(col) + k + 1]
        if patch.size == 0:
            return False
        rr, cc = np.nonzero(patch)
        return bool(
            len(rr) and (np.hypot(rr + r0 - row, cc + c0 - col).min() * self.grid.resolution <= within)
        )

    def contains(self, x: float, y: float, min_clearance: float = 0.0) -> bool:
        row, col = self.grid.world_to_cell(x, y)
        if not (0 <= row < self.label.shape[0] and 0 <= col < self.label.shape[1]):
            return False
        return bool(self.label[row, col] and self.clearance[row, col] >= min_clearance)
