"""A simulated scenario from the BIM: the circulation area, random starts, clutter and workers."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import StoreyModel
from bimtools.site.records import FREE, Obstacle, OccupancyGrid
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.geometry.se2 import Pose2D
from initcli.sim.world import Worker

__all__ = [
    "Circulation",
    "NoFreeSpace",
    "STACK_SIZE",
    "WORKER_ROOM_M",
    "place_clutter",
    "place_workers",
    "random_start",
]

STACK_SIZE = (1.2, 0.5)  # m: a pallet of material against a wall
WORKER_ROOM_M = 3.0  # m: at most this far past the end of its line a worker giving way walks


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


def random_start(circulation: Circulation, rng: np.random.Generator, clearance: float = 0.6) -> Pose2D:
    cells = circulation.cells(clearance)
    if len(cells) == 0:
        raise NoFreeSpace("no free corridor cell with enough clearance for a start pose")
    x, y = cells[int(rng.integers(len(cells)))]
    return Pose2D(float(x), float(y), float(rng.uniform(-math.pi, math.pi)))


def place_clutter(
    storey: StoreyModel, circulation: Circulation, density: float, rng: np.random.Generator
) -> list[np.ndarray]:
    """Material stacks against corridor walls, ``density`` per metre of corridor wall, kept off doors."""
    walls = [
        w
        for w in storey.walls
        if w.length >= STACK_SIZE[0] + 2.0
        and circulation.contains((w.x1 + w.x2) / 2 + 0.4 * w.normal[0], (w.y1 + w.y2) / 2 + 0.4 * w.normal[1])
    ]
    if not walls or density <= 0:
        return []
    lengths = np.array([w.length for w in walls])
    count = int(rng.poisson(density * lengths.sum()))
    features = np.array([[f.x, f.y] for f in storey.camera_features]).reshape(-1, 2)
    boxes: list[np.ndarray] = []
    for _ in range(count * 5):
        if len(boxes) >= count:
            break
        w = walls[int(rng.choice(len(walls), p=lengths / lengths.sum()))]
        s = rng.uniform(1.0, w.length - 1.0) / w.length
        px, py = w.x1 + s * (w.x2 - w.x1), w.y1 + s * (w.y2 - w.y1)
        if len(features) and np.hypot(features[:, 0] - px, features[:, 1] - py).min() < 1.8:
            continue
        if any(np.hypot(*(b.mean(axis=0)[:2] - [px, py])) < 3.0 for b in boxes):
            continue
        ux, uy = (w.x2 - w.x1) / w.length, (w.y2 - w.y1) / w.length
        nx, ny = w.normal
        half_l, depth = STACK_SIZE[0] / 2, STACK_SIZE[1]
        corners = np.array(
            [
                [px - ux * half_l + nx * 0.05, py - uy * half_l + ny * 0.05],
                [px + ux * half_l + nx * 0.05, py + uy * half_l + ny * 0.05],
                [px + ux * half_l + nx * (0.05 + depth), py + uy * half_l + ny * (0.05 + depth)],
                [px - ux * half_l + nx * (0.05 + depth), py - uy * half_l + ny * (0.05 + depth)],
            ]
        )
        boxes.append(np.vstack([corners, corners[:1]]))
    return boxes


def place_workers(
    storey: StoreyModel,
    circulation: Circulation,
    world_static: np.ndarray,
    count: int,
    rng: np.random.Generator,
) -> list[Worker]:
    """People walking back and forth along corridor walls (0.5 m off the wall, up to 8 m)."""
    walls = [
        w
        for w in storey.walls
        if w.length >= 4.0
        and circulation.contains((w.x1 + w.x2) / 2 + 0.5 * w.normal[0], (w.y1 + w.y2) / 2 + 0.5 * w.normal[1])
    ]
    workers: list[Worker] = []
    for _ in range(count * 10):
        if len(workers) >= count or not walls:
            break
        w = walls[int(rng.integers(len(walls)))]
        length = min(8.0, w.length - 1.0)
        s0 = rng.uniform(0.5, w.length - 0.5 - length)
        ux, uy = (w.x2 - w.x1) / w.length, (w.y2 - w.y1) / w.length
        offset = np.array(w.normal) * 0.5
        a = np.array([w.x1 + ux * s0, w.y1 + uy * s0]) + offset
        b = a + length * np.array([ux, uy])
        mid = (a + b) / 2
        if not circulation.contains(float(a[0]), float(a[1]), 0.3) or not circulation.contains(
            float(b[0]), float(b[1]), 0.3
        ):
            continue
        heading = math.atan2(uy, ux)
        free = float(ray_segment_distances(a, np.array([heading]), world_static, 12.0)[0])
        if free < length or float(np.hypot(*(mid - a))) < 1.0:
            continue  # clutter on the way
        # the room to step out of its line when giving way: free along the line beyond each end
        back, past = (
            float(ray_segment_distances(p, np.array([h]), world_static, WORKER_ROOM_M + 1.0)[0])
            for p, h in ((a, heading + math.pi), (b, heading))
        )
        workers.append(
            Worker(
                a=a,
                b=b,
                speed=float(rng.uniform(0.4, 1.0)),
                phase=float(rng.uniform(0, 2 * length)),
                room_a=float(np.clip(back - 1.0, 0.0, WORKER_ROOM_M)),
                room_b=float(np.clip(past - 1.0, 0.0, WORKER_ROOM_M)),
            )
        )
    return workers
