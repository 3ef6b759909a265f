"""A corridor with alcoves no two alike, its Nav2 map as a site, and a robot's recordings in it for
the watch: a control (the localiser right all along) and a kidnap (the robot carried from the
corridor's west part to its east end, the localiser carried on by odometry from where it was)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import box

from bimtools.extract.from_map import extract_map_site, write_map_site
from bimtools.site.occupancy_map import write_map
from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from initcli.core.geometry.se2 import Pose2D
from initcli.io.log_records import NO_CAMERA, NO_MOUNT, Localiser, Meta, Odom, Record, Scan
from tests.landmark_worlds import BEAMS, RANGE_MAX, World, walled

RESOLUTION = 0.05
STEP_M = 0.1  # m between two poses of a drive (1 m/s at 10 Hz)
# (x, width, depth) of the alcoves north (depth > 0) and south (< 0) of the corridor
ALCOVES = (
    (2.0, 3.0, 3.5),
    (7.5, 1.5, 1.2),
    (11.0, 4.0, 2.0),
    (17.0, 2.0, 5.0),
    (21.5, 3.5, 1.0),
    (26.0, 2.5, 3.0),
    (4.5, 2.0, -2.5),
    (13.5, 1.0, -1.5),
    (19.0, 5.0, -3.0),
    (27.5, 1.5, -1.0),
)
CORRIDOR = (30.0, 2.4)


def corridor_world() -> World:
    length, width = CORRIDOR
    parts = [box(0.0, 0.0, length, width)]
    for x, w, d in ALCOVES:
        parts.append(box(x, width, x + w, width + d) if d > 0 else box(x, d, x + w, 0.0))
    return walled(shapely.union_all(parts))


def world_grid(world: World) -> OccupancyGrid:
    low = np.array(world.solid.bounds[:2]) - 1.0
    high = np.array(world.solid.bounds[2:]) + 1.0
    cols, rows = np.ceil((high - low) / RESOLUTION).astype(int)
    xs = low[0] + (np.arange(cols) + 0.5) * RESOLUTION
    ys = low[1] + (np.arange(rows)[::-1] + 0.5) * RESOLUTION  # row 0 at the top
    gx, gy = np.meshgrid(xs, ys)
    cells = np.full((rows, cols), UNKNOWN, np.uint8)
    cells[shapely.contains_xy(world.rooms, gx, gy)] = FREE
    cells[shapely.contains_xy(world.solid.buffer(0.03), gx, gy)] = OCCUPIED
    return OccupancyGrid(cells, RESOLUTION, (float(low[0]), float(low[1]), 0.0))


def write_world_site(folder: Path) -> Path:
    """The corridor's map as ``bim-extract MAP.yaml -o SITE`` writes it."""
    folder.mkdir(parents=True, exist_ok=True)
    yaml_path = folder / "corridor.yaml"
    write_map(yaml_path, world_grid(corridor_world()))
    site = folder / "corridor_site"
    write_map_site(site, extract_map_site(yaml_path), preview=False)
    return site


def drive(start: Pose2D, metres: float) -> list[Pose2D]:
    """Poses every STEP_M along a straight drive from ``start``."""
    n = int(round(metres / STEP_M))
    return [start * Pose2D(k * STEP_M, 0.0, 0.0) for k in range(n + 1)]


@dataclass
class Recording:
    records: list[Record]
    truth: list[tuple[float, Pose2D]]  # (t, true pose in the map frame)
    splice_t: float | None

    def truth_at(self, t: float) -> Pose2D:
        return min(self.truth, key=lambda s: abs(s[0] - t))[1]


def record(world: World, legs: list[list[Pose2D]], rng: np.random.Generator, t0: float = 0.0) -> Recording:
    """Drive ``legs`` one after the other (carried between them, the wheels unaware): odometry on
    (1 % scale drift), a scan at each pose, and the localiser's pose: right on the first leg, then
    carried on by odometry from where the first leg ended."""
    scale = 1.01
    records: list[Record] = [Meta(NO_CAMERA, NO_MOUNT, camera_absent=True, source="kidnap_world")]
    truth: list[tuple[float, Pose2D]] = []
    odom = Pose2D(0.0, 0.0, 0.0)
    stale: Pose2D | None = None
    t, splice = t0, None
    for i, leg in enumerate(legs):
        if i == 1:
            stale = legs[0][-1] * odom.inverse()  # the localiser's odom -> map when carried
            splice = t
        for k, pose in enumerate(leg):
            if k:
                step = leg[k - 1].inverse() * pose
                odom = odom * Pose2D(step.x * scale, step.y * scale, step.yaw)
            t += STEP_M
            ranges, a0, inc = world.scan(pose.x, pose.y, pose.yaw, rng)
            records.append(Odom(t, odom.x, odom.y, odom.yaw))
            records.append(Scan(t + 0.001, a0, inc, RANGE_MAX, tuple(float(r) for r in ranges)))
            seen = pose if stale is None else stale * odom
            records.append(Localiser(t + 0.002, seen.x, seen.y, seen.yaw))
            truth.append((t, pose))
    return Recording(records, truth, splice)


def control(world: World, rng: np.random.Generator) -> Recording:
    return record(world, [drive(Pose2D(1.0, 1.2, 0.0), 27.0)], rng)


def kidnap(world: World, rng: np.random.Generator) -> Recording:
    """East along the corridor's west part, then carried to its east end and driven west."""
    return record(world, [drive(Pose2D(1.0, 1.2, 0.0), 9.0), drive(Pose2D(29.0, 1.2, math.pi), 24.0)], rng)


__all__ = ["BEAMS", "Recording", "control", "corridor_world", "kidnap", "write_world_site"]
