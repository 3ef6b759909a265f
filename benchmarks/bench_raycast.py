"""Benchmark of the simulated lidar: ms per 360-beam scan (20 m) on each sample storey.

"before" is the brute force kept as :func:`initcli.core.geometry.raycast.ray_segment_distances` (every ray
against every static segment the grid index returns within range, plus the workers), as
``SimWorld.raycast`` did it; "after" is ``SimWorld.raycast`` now (:func:`cast_rays`). Scans are cast
from random free cells of the storey's occupancy map at random headings; the two answers are
checked to agree. Times are the best of ``--repeats`` passes over the same scans.

Usage: ``.venv/bin/python benchmarks/bench_raycast.py [--quick] [--scans 200] [--repeats 5]``
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from _common import SAMPLES, parse_args

from bimtools.site.records import FREE
from initcli.config import load_config
from initcli.config.building import choose_storey, prepare_site
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.sim.build import build_sim
from initcli.sim.driver import LidarSpec
from initcli.sim.world import SimWorld

STOREYS = ("ntu_hallway", "block_a", "block_b")


def load_world(name: str, workdir: Path, seed: int = 0) -> tuple[SimWorld, np.ndarray]:
    """The sample's simulated world and the (n, 2) centres of its storey's free map cells."""
    config = load_config(SAMPLES / f"{name}.site.yaml")
    site = prepare_site(config, workdir)
    storey, _ = choose_storey(config, site)
    world = build_sim(config, site, storey, seed).world
    grid = site.storeys[storey].grid
    assert grid is not None
    rows, cols = np.nonzero(grid.cells == FREE)
    x, y = grid.cell_centre(rows, cols)
    return world, np.column_stack([x, y])


def old_segments_near(world: SimWorld, x: float, y: float, radius: float) -> np.ndarray:
    """The pre-optimisation ``SimWorld.segments_near`` (no cache of the cell blocks' segments)."""
    g0 = np.floor((np.array([x, y]) - radius) / world.cell).astype(int)
    g1 = np.floor((np.array([x, y]) + radius) / world.cell).astype(int)
    ids = [
        world._index[(gx, gy)]
        for gx in range(g0[0], g1[0] + 1)
        for gy in range(g0[1], g1[1] + 1)
        if (gx, gy) in world._index
    ]
    if not ids:
        return np.zeros((0, 4))
    return world.static[np.unique(np.concatenate(ids))]


def brute_force_scan(world: SimWorld, origin: np.ndarray, angles: np.ndarray, max_range: float) -> np.ndarray:
    """The pre-optimisation ``SimWorld.raycast`` at t = 0."""
    near = old_segments_near(world, float(origin[0]), float(origin[1]), max_range)
    moving = world.worker_segments(0.0)
    segments = np.concatenate([near, moving]) if len(moving) else near
    return ray_segment_distances(origin, angles, segments, max_range)


def new_scan(world: SimWorld, origin: np.ndarray, angles: np.ndarray, max_range: float) -> np.ndarray:
    """``SimWorld.raycast`` at t = 0."""
    return world.raycast(origin, angles, max_range, 0.0)


Scan = Callable[[SimWorld, np.ndarray, np.ndarray, float], np.ndarray]


def best_ms(
    scan: Scan, world: SimWorld, origins: np.ndarray, angles: list[np.ndarray], max_range: float, repeats: int
) -> float:
    """Best over ``repeats`` passes of the mean ms per scan."""
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for origin, a in zip(origins, angles, strict=True):
            scan(world, origin, a, max_range)
        best = min(best, (time.perf_counter() - t0) / len(origins) * 1e3)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=5)
    args = parse_args(parser, quick={"scans": 20, "repeats": 1})
    lidar = LidarSpec()
    base = lidar.angle_min + lidar.angle_increment * np.arange(lidar.beams)
    rng = np.random.default_rng(0)
    print(f"{lidar.beams} beams, max range {lidar.max_range} m, {args.scans} scans, best of {args.repeats}")
    print(f"{'storey':<12} {'segments':>8} {'before ms':>10} {'after ms':>9} {'speed-up':>9}")
    with tempfile.TemporaryDirectory() as tmp:
        for name in STOREYS:
            world, free = load_world(name, Path(tmp) / name)
            origins = free[rng.choice(len(free), args.scans)]
            angles = [base + yaw for yaw in rng.uniform(-math.pi, math.pi, args.scans)]
            r = lidar.max_range
            for origin, a in zip(origins, angles, strict=True):
                old, new = brute_force_scan(world, origin, a, r), new_scan(world, origin, a, r)
                assert np.array_equal(old, new), f"{name}: scans differ at {origin}"
            before = best_ms(brute_force_scan, world, origins, angles, r, args.repeats)
            after = best_ms(new_scan, world, origins, angles, r, args.repeats)
            print(f"{name:<12} {len(world.static):>8} {before:>10.3f} {after:>9.3f} {before / after:>8.1f}x")


if __name__ == "__main__":
    main()
