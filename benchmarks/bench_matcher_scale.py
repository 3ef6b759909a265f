"""Benchmark: Algorithm 1's incremental matcher (``Matcher.extend``, as the session and ``bim-init
match`` call it) on BIM tables with lidar landmarks, where corners make most of the features.

Goals (issue 32, speed): <= 1 ms median per update at 1,000 features, <= 10 ms at 10,000.

The floors are synthetic: corridors 12 m apart, rooms on both sides 3-5 m wide and 5 m deep, each
with a door and an opening on the corridor (the door's recess), four concave corners, and in a
quarter of them a pillar (four convex corners) or a column (four column corners); a lift and a
staircase at each corridor's ends. About 70 % of the features are corners. The detected sequence
is what a robot sees walking along a corridor and through a room: a door, its opening, the room's
corners, the next door and so on, in a random odom frame with 5 cm noise. Each update is one
``Matcher.extend`` with the shipped settings (``MatchOptions``' defaults: alpha 0.8 m between camera
features, landmark_alpha 0.15 m plus landmark_drift between two landmarks, beta 15 degrees, one camera
outlier, revisits; with doors in the sequence every landmark may be an outlier and only doors start a
candidate, lidar alone the landmarks' own outlier share), timed on one core in CPU time (the process's:
other work on a shared machine does not count); the table gives the median and p95 over all updates
of all sequences, per size, and each size's ratio to its goal, for sequences with the doors and for
lidar alone (the camera saw nothing: the sequence starts at a corner, whose class has thousands of
members), the latter also with the landmarks matched like camera features (``--no-landmarks``:
alpha 0.8 m, the camera's outlier budget), with the partial matches alive after each update (the
cost of an update grows with them).

Usage: ``.venv/bin/python benchmarks/bench_matcher_scale.py [--quick] [--profile]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import cProfile  # noqa: E402
import math  # noqa: E402
import pstats  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
from _common import parse_args  # noqa: E402  (benchmarks/ is the script's folder)
from bench_match import pin_one_core  # noqa: E402

from initcli.core.features.classes import ClassMap  # noqa: E402
from initcli.core.geometry.se2 import Pose2D  # noqa: E402
from initcli.core.hypotheses.matching import BimIndex, Matcher, MatchState  # noqa: E402
from initcli.match.pipeline import MatchOptions  # noqa: E402

GOALS_MS = {1_000: 1.0, 10_000: 10.0}  # median ms per update
CORRIDOR_SPACING = 12.0  # m
ROOM_DEPTH = 5.0  # m
NOISE = 0.05  # m: detected positions (lidar landmarks are centimetres; doors a little worse)


@dataclass
class Room:
    features: list[int]  # in the order a robot sees them: door, opening, then the corners


@dataclass
class Floor:
    xy: np.ndarray
    classes: list[str]
    rooms: list[Room]


def make_floor(n_target: int, seed: int) -> Floor:
    rng = np.random.default_rng(seed)
    xy: list[tuple[float, float]] = []
    classes: list[str] = []
    rooms: list[Room] = []

    def add(cls: str, x: float, y: float) -> int:
        xy.append((x, y))
        classes.append(cls)
        return len(xy) - 1

    length = max(30.0, math.sqrt(n_target * 1.2))
    k = 0
    while len(xy) < n_target:
        yc = k * CORRIDOR_SPACING
        add("Lift", 0.0, yc)
        add("Stairs", length, yc)
        for side in (-1.0, 1.0):
            wall = yc + side * 1.0
            x = 0.5
            while x < length - 3.0 and len(xy) < n_target:
                width = float(rng.uniform(3.0, 5.0))
                far = wall + side * ROOM_DEPTH
                door_x = x + float(rng.uniform(0.6, width - 0.6))
                seen = [add("Door", door_x, wall), add("Opening", door_x, wall)]
                seen += [
                    add("ConcaveCorner", cx, cy)
                    for cx, cy in ((x, wall), (x + width, wall), (x + width, far), (x, far))
                ]
                if rng.random() < 0.25:
                    cls = "ColumnCorner" if rng.random() < 0.5 else "ConvexCorner"
                    half = 0.2 if cls == "ColumnCorner" else 0.6
                    px, py = x + width / 2, (wall + far) / 2
                    seen += [
                        add(cls, px + sx * half, py + sy * half)
                        for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
                    ]
                rooms.append(Room(seen))
                x += width + 0.2
        k += 1
    return Floor(
        np.array(xy[:n_target]), classes[:n_target], [r for r in rooms if max(r.features) < n_target]
    )


def walk(floor: Floor, rng: np.random.Generator, n: int, lidar_only: bool) -> tuple[np.ndarray, list[str]]:
    """n features seen through consecutive rooms on one side of a corridor, in a random odom frame
    (``lidar_only``: the camera saw nothing, the doors are left out)."""
    start = int(rng.integers(len(floor.rooms) - 4))
    seq: list[int] = []
    for room in floor.rooms[start:]:
        seq += [i for i in room.features if not (lidar_only and floor.classes[i] == "Door")]
        if len(seq) >= n:
            break
    seq = seq[:n]
    to_odom = Pose2D(*rng.uniform(-50, 50, 2), rng.uniform(-math.pi, math.pi))
    xy = to_odom.apply(floor.xy[seq]) + rng.normal(0.0, NOISE, (len(seq), 2))
    return xy, [floor.classes[i] for i in seq]


def bench(
    size: int, sequences: int, length: int, lidar_only: bool, options: MatchOptions, profile: bool
) -> tuple[list[float], list[int], Counter]:
    floor = make_floor(size, seed=size)
    cmap = ClassMap()
    index = BimIndex(floor.xy, [cmap.canonical(c) for c in floor.classes])
    # as bim-init match sets them: with doors in the sequence every landmark may be an outlier and
    # only doors start a candidate; lidar alone, the landmarks' outlier share
    matcher = Matcher(index, options.match_params(camera=not lidar_only))
    rng = np.random.default_rng(7)
    times: list[float] = []
    partials: list[int] = []
    profiler = cProfile.Profile() if profile else None
    for _ in range(sequences):
        xy, cls = walk(floor, rng, length, lidar_only)
        state = MatchState.empty()
        for p, c in zip(xy, cls, strict=True):
            t0 = time.process_time()
            if profiler is not None:
                profiler.enable()
            state = matcher.extend(state, p, cmap.canonical(c))
            if profiler is not None:
                profiler.disable()
            times.append((time.process_time() - t0) * 1e3)
            partials.append(len(state))
    if profiler is not None:
        print(f"\n--- profile, {size} features{', lidar only' if lidar_only else ''} ---")
        pstats.Stats(profiler).sort_stats("cumulative").print_stats(12)
    return times, partials, Counter(floor.classes)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sequences", type=int, default=30, help="detected-feature sequences per size")
    parser.add_argument("--length", type=int, default=10, help="detected features per sequence")
    parser.add_argument("--profile", action="store_true", help="cProfile the updates of each size")
    args = parse_args(parser, quick={"sequences": 5, "length": 8})
    sequences, length = args.sequences, args.length
    print(f"bench_matcher_scale: {pin_one_core()}; python {sys.version.split()[0]}, numpy {np.__version__}")
    print(f"{sequences} sequences of {length} detected features per size; ms per Matcher.extend")
    print(
        "| features | corners | sequence | alpha m (landmarks) | median ms | p95 ms | max ms | "
        "partial matches (median / max) | goal (median) | ratio to goal |"
    )
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    shipped, as_camera = MatchOptions(), MatchOptions(landmarks=False)
    # the shipped settings, and for lidar alone the landmarks matched like camera features
    cases = [(False, shipped), (True, shipped), (True, as_camera)]
    for lidar_only, options in cases:
        alpha = (
            f"{options.alpha:g} ({options.landmark_alpha:g})" if options.landmarks else f"{options.alpha:g}"
        )
        for size, goal in GOALS_MS.items():
            times, partials, mix = bench(size, sequences, length, lidar_only, options, args.profile)
            corners = sum(v for k, v in mix.items() if k.endswith("Corner")) / size
            median, p95 = float(np.median(times)), float(np.percentile(times, 95))
            print(
                f"| {size:,} | {corners:.0%} | {'lidar only' if lidar_only else 'doors and landmarks'} | "
                f"{alpha} | {median:.2f} | {p95:.2f} | {max(times):.2f} | "
                f"{int(np.median(partials)):,} / {max(partials):,} | <= {goal:g} | "
                f"{median / goal:.2f} ({'met' if median <= goal else 'MISSED'}) |"
            )


if __name__ == "__main__":
    main()
