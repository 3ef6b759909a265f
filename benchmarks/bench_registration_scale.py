"""Benchmark: the lidar submap registration (:func:`initcli.core.lidar.registration.register`, as a
session and ``bim-init match`` call it with the camera off) against the map's area.

Goal (issue "Real sensors"): a 60 m window on a 120 x 120 m map matched in at most 30 s on 2 cores.

The maps are synthetic offices drawn into an :class:`~bimtools.site.records.OccupancyGrid` at 0.05 m
(the resolution ``bim-extract`` writes): corridors 2 m wide on a grid about 11 m apart, the blocks
between them split into two rows of rooms of random widths, each room with a door opening onto its
corridor, walls 0.15 m thick, unknown outside the outer wall. The robot walks ``--window`` m along
the corridors (from a crossing, a random turn at each crossing, never straight back); a simulated
lidar (the session's defaults: ``lidar.beams`` beams over ``lidar.fov``, ``lidar.max_range``,
``lidar.noise``, ``lidar.dropout``), ray cast against the walls
(:func:`initcli.core.geometry.raycast.cast_rays`), scans every 0.25 m of travel; odometry is the
truth. The scans go into :class:`~initcli.verify.evidence.PathEvidence` as a session adds them, and
every ``registration.every`` m from ``registration.min_travel`` on the submap of the last
``registration.window`` m is built as :class:`~initcli.verify.registration.SubmapRegistration` builds
it (every beam's scan, ``registration.wall_lines``, then thinned) and registered over the map
(prepared once, as ``SubmapRegistration.maps`` prepares a storey without doors). All settings are
``RegistrationParams``' and ``VerificationParams``' defaults.

Printed per size: the map's preparation (once per session), the seconds per registration (mean and
largest), the seconds per window (the sum of the window's registrations, what a session or
``bim-init match`` spends on them), whether the last registration was unique and its error against
the truth; then the growth exponent (the log-log slope of the seconds per window against the area:
1 grows with the area) and the goal's check, a number against 30 s, not a test. Wall-clock time on
the cores the machine has (OpenCV's own threads included).

Usage: ``.venv/bin/python benchmarks/bench_registration_scale.py [--quick] [--sizes 30,60] [--seed N]``
"""

from __future__ import annotations

import argparse
import math
import os
import time
from dataclasses import dataclass

import cv2
import numpy as np
from _common import parse_args

from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from initcli.config import SessionConfig
from initcli.core.filters.particle_filter import likelihood_field
from initcli.core.geometry.raycast import cast_rays
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.registration import Registration, RegistrationMap, register
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.scan_fit import BeamEnds, ScanSample
from initcli.core.lidar.wall_beams import wall_beams
from initcli.verify.evidence import SCAN_BEAM_STEP, TRACK_BEAM_STEP, PathEvidence

GOAL_SIZE_M = 120.0  # the goal's map: 120 x 120 m ...
GOAL_WINDOW_M = 60.0  # ... a 60 m window on it ...
GOAL_S = 30.0  # ... matched in at most this many seconds (2 cores)
RESOLUTION = 0.05  # m per cell, as bim-extract writes its maps
PITCH = 11.0  # m between corridor centre lines
CORRIDOR = 2.0  # m: corridor width
WALL = 0.15  # m: wall thickness
DOOR = 0.9  # m: door opening
MARGIN = 1.0  # m of unknown round the outer wall
SCAN_STEP_M = 0.25  # m of travel between simulated scans


@dataclass
class Office:
    size: float
    grid: OccupancyGrid
    segments: np.ndarray  # (N, 4) wall outlines for the ray casting
    lines: list[float]  # corridor centre lines (the same in x and y)


Rect = tuple[float, float, float, float]  # x0, y0, x1, y1


def _walls(size: float, rng: np.random.Generator) -> tuple[list[Rect], list[Rect], list[float]]:
    """The office's wall rectangles, its door openings (x0, x1 along a corridor wall and that wall's
    y0) and its corridor centre lines (the same in x and y)."""
    half = CORRIDOR / 2
    count = max(2, int(round((size - CORRIDOR) / PITCH)) + 1)
    lines = [float(v) for v in np.linspace(WALL + half, size - WALL - half, count)]
    doors: list[tuple[float, float, float]] = []
    walls: list[Rect] = [(0.0, 0.0, size, WALL), (0.0, size - WALL, size, size)]
    walls += [(0.0, 0.0, WALL, size), (size - WALL, 0.0, size, size)]
    for a, b in zip(lines[:-1], lines[1:], strict=True):  # each block between two corridors, both ways
        for c, d in zip(lines[:-1], lines[1:], strict=True):
            x0, x1, y0, y1 = a + half, b - half, c + half, d - half
            mid = (y0 + y1) / 2
            walls += [(x0, y0 - WALL, x1, y0), (x0, y1, x1, y1 + WALL)]  # corridor walls, doors cut below
            walls += [
                (x0 - WALL, y0, x0, y1),
                (x1, y0, x1 + WALL, y1),
                (x0, mid - WALL / 2, x1, mid + WALL / 2),
            ]
            for lo, hi, wall_y in ((y0, mid, y0 - WALL), (mid, y1, y1)):  # the two rows of rooms
                x = x0
                while x < x1 - 2.5:
                    width = min(float(rng.uniform(2.5, 5.0)), x1 - x)
                    if x1 - (x + width) < 2.5:
                        width = x1 - x
                    if x + width < x1:
                        walls.append((x + width - WALL / 2, lo, x + width + WALL / 2, hi))
                    door = x + float(rng.uniform(0.3, max(0.31, width - DOOR - 0.3)))
                    doors.append((door, door + DOOR, wall_y))
                    x += width
    return walls, doors, lines


def make_office(size: float, seed: int) -> Office:
    rng = np.random.default_rng(seed)
    walls, doors, lines = _walls(size, rng)
    pieces: list[Rect] = []
    for x0, y0, x1, y1 in walls:  # cut the door openings out of the corridor walls
        cuts = sorted((a, b) for a, b, y in doors if abs(y - y0) < 1e-9 and x0 <= a < x1)
        for a, b in cuts:
            pieces.append((x0, y0, a, y1))
            x0 = b
        pieces.append((x0, y0, x1, y1))
    pieces = [p for p in pieces if p[2] - p[0] > 1e-6 and p[3] - p[1] > 1e-6]
    n = int(math.ceil((size + 2 * MARGIN) / RESOLUTION))
    cells = np.full((n, n), UNKNOWN, np.uint8)
    inner = slice(int(MARGIN / RESOLUTION), int((MARGIN + size) / RESOLUTION))
    cells[inner, inner] = FREE
    origin = (-MARGIN, -MARGIN, 0.0)
    for x0, y0, x1, y1 in pieces:
        c0, c1 = (int(round((v + MARGIN) / RESOLUTION)) for v in (x0, x1))
        r0, r1 = (n - int(round((v + MARGIN) / RESOLUTION)) for v in (y1, y0))  # row 0 is the top
        cells[r0 : max(r1, r0 + 1), c0 : max(c1, c0 + 1)] = OCCUPIED
    grid = OccupancyGrid(cells, RESOLUTION, origin)
    segments = np.array(
        [
            s
            for x0, y0, x1, y1 in pieces
            for s in ((x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0))
        ],
        dtype=float,
    )
    return Office(size, grid, segments, lines)


def walk(office: Office, length: float, rng: np.random.Generator) -> list[Pose2D]:
    """Poses every SCAN_STEP_M m along ``length`` m of corridor centre lines, from a crossing near
    the middle, a random turn at each crossing (never straight back)."""
    lines = office.lines
    k = len(lines) // 2
    node = (k, k)
    heading: tuple[int, int] | None = None
    corners = [(lines[k], lines[k])]
    travelled = 0.0
    while travelled < length:
        moves = [
            m
            for m in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= node[0] + m[0] < len(lines)
            and 0 <= node[1] + m[1] < len(lines)
            and (heading is None or m != (-heading[0], -heading[1]))
        ]
        heading = moves[int(rng.integers(len(moves)))]
        node = (node[0] + heading[0], node[1] + heading[1])
        corners.append((lines[node[0]], lines[node[1]]))
        travelled += math.dist(corners[-2], corners[-1])
    poses: list[Pose2D] = []
    done = 0.0
    for (ax, ay), (bx, by) in zip(corners[:-1], corners[1:], strict=True):
        leg = math.dist((ax, ay), (bx, by))
        yaw = math.atan2(by - ay, bx - ax)
        s = 0.0
        while s < leg and done + s <= length + 1e-9:
            poses.append(Pose2D(ax + (bx - ax) * s / leg, ay + (by - ay) * s / leg, yaw))
            s += SCAN_STEP_M
        done += leg
    return poses


def scan(
    office: Office, pose: Pose2D, angles: np.ndarray, cfg: SessionConfig, rng: np.random.Generator
) -> np.ndarray:
    """One simulated scan's ranges at ``pose`` (inf: no return)."""
    lidar = cfg.lidar
    ranges = cast_rays(np.array([pose.x, pose.y]), pose.yaw + angles, office.segments, lidar.max_range)
    ranges = ranges + rng.normal(0.0, lidar.noise, len(ranges))
    ranges[(ranges >= lidar.max_range) | (rng.random(len(ranges)) < lidar.dropout)] = math.inf
    return ranges


def submap(path: PathEvidence, params: RegistrationParams) -> list[ScanSample]:
    """The submap's scans as ``SubmapRegistration`` gathers them (its ``_submap_scans``)."""
    lines = params.wall_lines
    scans, _ = path.along(params.window, raw=lines > 0)
    newest = path.latest_raw if lines > 0 else (path.scans[-1] if path.scans else None)
    if newest is not None and (not scans or newest.odom != scans[-1].odom):
        scans = [*scans, newest]
    if lines <= 0:
        return scans
    step = SCAN_BEAM_STEP * TRACK_BEAM_STEP
    thinned = []
    for s in scans:
        w = wall_beams(s, lines)
        thinned.append(ScanSample(w.odom, w.angles[::step], w.ranges[::step], w.range_max))
    return thinned


@dataclass
class Result:
    size: float
    prepare_s: float
    times: list[float]  # wall-clock s of each registration
    cpu: list[float]  # the process's CPU s of each (OpenCV's threads included)
    last: Registration
    truth: Pose2D


def run_size(size: float, args: argparse.Namespace) -> Result:
    cfg = SessionConfig()
    params = cfg.registration
    tolerance = cfg.verification.scan_tolerance
    rng = np.random.default_rng(args.seed + int(size))
    office = make_office(size, args.seed + int(size))
    started = time.perf_counter()
    field_ = likelihood_field(office.grid)
    maps = [RegistrationMap("office", office.grid, field_, through=field_, fit=field_)]
    prepare = time.perf_counter() - started
    fov = math.radians(cfg.lidar.fov)
    angles = -fov / 2 + fov / cfg.lidar.beams * np.arange(cfg.lidar.beams)
    path = PathEvidence()
    times: list[float] = []
    cpu: list[float] = []
    next_at = params.min_travel
    last: Registration | None = None
    truth = Pose2D(0.0, 0.0, 0.0)
    for i, pose in enumerate(walk(office, args.window, rng)):
        travel = i * SCAN_STEP_M
        path.add_scan(pose, travel, angles, scan(office, pose, angles, cfg, rng), cfg.lidar.max_range)
        if params.enabled and travel >= next_at:
            next_at = travel + params.every
            t0, c0 = time.perf_counter(), time.process_time()
            last = register(BeamEnds.of(submap(path, params)), maps, params, tolerance)
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            truth = pose
    assert last is not None
    return Result(size, prepare, times, cpu, last, truth)


def slope(areas: list[float], seconds: list[float]) -> float:
    return float(np.polyfit(np.log(areas), np.log(seconds), 1)[0])


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", default="30,60,120,180", help="map sides in m, comma-separated")
    parser.add_argument("--window", type=float, default=GOAL_WINDOW_M, help="m of travel of the window")
    parser.add_argument("--seed", type=int, default=1)
    args = parse_args(parser, {"sizes": "30,60", "window": 10.0})
    sizes = [float(s) for s in args.sizes.split(",") if s]
    params = RegistrationParams()
    print(
        f"registration every {params.every:g} m from {params.min_travel:g} m, a {params.window:g} m submap,"
        f" wall_lines {params.wall_lines:g} m; a {args.window:g} m window; {os.cpu_count()} cores,"
        f" OpenCV threads {cv2.getNumThreads()}",
        flush=True,
    )
    print(
        "| map | area m² | prepare s | registrations | s per registration: mean, max (CPU mean)"
        " | s per window (CPU) | last: unique, error |"
    )
    print("|---|---|---|---|---|---|---|")
    results = []
    for size in sizes:
        r = run_size(size, args)
        results.append(r)
        best = r.last.best
        error = (
            f"{best.pose.distance_to(r.truth):.2f} m, {math.degrees(best.pose.yaw_error(r.truth)):.1f} deg"
            if best is not None
            else "-"
        )
        print(
            f"| {size:g} x {size:g} m | {size * size:.0f} | {r.prepare_s:.2f} | {len(r.times)}"
            f" | {np.mean(r.times):.2f}, {max(r.times):.2f} ({np.mean(r.cpu):.2f})"
            f" | {sum(r.times):.1f} ({sum(r.cpu):.1f}) | {'yes' if r.last.unique else 'no'}, {error} |",
            flush=True,
        )
    areas = [r.size**2 for r in results]
    mean_s = [float(np.mean(r.times)) for r in results]
    exponent = slope(areas, mean_s) if len(results) >= 2 else None
    if exponent is not None:
        print(f"growth exponent (log-log slope of s per registration against area): {exponent:.2f}")
    goal = next((r for r in results if r.size == GOAL_SIZE_M), None)
    head = (
        f"goal: a {GOAL_WINDOW_M:g} m window on {GOAL_SIZE_M:g} x {GOAL_SIZE_M:g} m"
        f" in <= {GOAL_S:g} s on 2 cores:"
    )
    if goal is not None and args.window == GOAL_WINDOW_M:
        spent = sum(goal.times)
        verdict = "met" if spent <= GOAL_S else "NOT met"
        print(f"{head} {spent:.1f} s ({spent / GOAL_S:.2f} of the goal): {verdict}")
    elif exponent is not None:
        count = int((GOAL_WINDOW_M - params.min_travel) // params.every) + 1  # registrations in the window
        estimate = count * mean_s[-1] * (GOAL_SIZE_M**2 / areas[-1]) ** exponent
        print(f"{head} not measured here; extrapolated from the sizes above {estimate:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
