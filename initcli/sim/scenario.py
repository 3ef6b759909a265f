"""A simulated scenario from the BIM: random starts in the circulation area, clutter and workers."""

from __future__ import annotations

import math

import numpy as np

from bimtools.site.load import StoreyModel
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.geometry.se2 import Pose2D
from initcli.sim.world import Worker
from initcli.storey.circulation import Circulation, NoFreeSpace

__all__ = [
    "STACK_SIZE",
    "WORKER_ROOM_M",
    "place_clutter",
    "place_workers",
    "random_start",
]

STACK_SIZE = (1.2, 0.5)  # m: a pallet of material against a wall
WORKER_ROOM_M = 3.0  # m: at most this far past the end of its line a worker giving way walks


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
