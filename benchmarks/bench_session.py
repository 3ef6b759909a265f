"""Benchmark ``bim-init run`` on the simulated robot: the issue's goals, measured.

- sessions: ``--starts`` random corridor starts (seeds 1..N) on each sample model, oracle
  detector, default configs: success rate, mean/max fine error, mean coarse distance (paper: 44.9 m
  NTU, 14.8 m block A, 16.6 m block B), confident wrong results, and the simulation speed
  (simulated seconds per wall-clock second);
- the particle-filter update (predict + likelihood-field update + resampling) with 2,000
  particles and 60 beams (goal <= 10 ms).

    python benchmarks/bench_session.py [--quick] [--starts 20] [--workers 2]
                                       [--models block_a,block_b,ntu_hallway]
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from _common import SAMPLES, parse_args

PAPER_DISTANCE = {"ntu_hallway": 44.88, "block_a": 14.81, "block_b": 16.61}


def one_session(args: tuple[str, int, str]) -> dict:
    name, seed, workdir = args
    from initcli.config import load_config
    from initcli.config.building import prepare_site
    from initcli.session.simulated import sim_session

    config = load_config(SAMPLES / f"{name}.site.yaml")
    site = prepare_site(config, Path(workdir) / name)
    result = sim_session(config, site, seed).session.run()
    trans, rot = result.errors()
    wrong = result.success and (trans["fine"] or 0.0) > 1.0
    return {
        "name": name,
        "seed": seed,
        "success": result.success,
        "reason": result.reason,
        "fine_m": trans["fine"],
        "fine_deg": rot["fine"],
        "coarse_m": trans["coarse"],
        "distance_coarse": result.distance_coarse_m,
        "sim_s": result.duration_s,
        "wall_s": result.wall_seconds,
        "confident_wrong": wrong,
    }


def bench_particle_filter(repeats: int = 50) -> float:
    from bimtools.extract.pipeline import extract_site
    from initcli.core.filters.particle_filter import FilterNoise, LaserModel, LikelihoodField, ParticleFilter
    from initcli.core.geometry.se2 import Pose2D

    site = extract_site(SAMPLES / "block_a.ifc")
    grid = site.storeys[0].grid
    rng = np.random.default_rng(0)
    pf = ParticleFilter(LikelihoodField(grid), 2000, FilterNoise(), LaserModel(), rng)
    pf.seed(Pose2D(30.0, 11.0, 0.0), 0.3, 0.1)
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    ranges = rng.uniform(0.5, 8.0, 360)
    start = time.perf_counter()
    for _ in range(repeats):
        pf.predict((0.01, 0.25, 0.0))
        pf.update(angles, ranges, 20.0)
        pf.resample()
    return (time.perf_counter() - start) / repeats * 1000


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--starts", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--models", default="block_a,block_b,ntu_hallway")
    parser.add_argument("--pf-repeats", type=int, default=50, help="particle-filter updates timed")
    args = parse_args(parser, quick={"starts": 1, "pf_repeats": 5})
    pf_ms = bench_particle_filter(args.pf_repeats)
    print(f"particle filter update, 2000 particles x 60 beams: {pf_ms:.2f} ms (goal <= 10 ms)")
    names = args.models.split(",")
    with tempfile.TemporaryDirectory() as workdir:
        jobs = [(n, s, workdir) for n in names for s in range(1, args.starts + 1)]
        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            rows = list(pool.map(one_session, jobs))
    print(
        f"\n{'model':12s} {'success':>8s} {'fine m':>7s} {'max m':>6s} {'fine deg':>8s} {'coarse m':>8s} "
        f"{'dist m':>7s} {'paper m':>7s} {'wrong':>5s} {'x realtime':>10s}"
    )
    for name in names:
        r = [row for row in rows if row["name"] == name]
        ok = [row for row in r if row["success"]]
        fine = [row["fine_m"] for row in ok if row["fine_m"] is not None]
        deg = [row["fine_deg"] for row in ok if row["fine_deg"] is not None]
        coarse = [row["coarse_m"] for row in ok if row["coarse_m"] is not None]
        dist = [row["distance_coarse"] for row in ok if row["distance_coarse"] is not None]
        speed = sum(row["sim_s"] for row in r) / max(sum(row["wall_s"] for row in r), 1e-9)
        print(
            f"{name:12s} {len(ok):>4d}/{len(r):<3d} {statistics.mean(fine or [math.nan]):7.3f} "
            f"{max(fine or [math.nan]):6.3f} {statistics.mean(deg or [math.nan]):8.2f} "
            f"{statistics.mean(coarse or [math.nan]):8.3f} {statistics.mean(dist or [math.nan]):7.1f} "
            f"{PAPER_DISTANCE.get(name, math.nan):7.1f} {sum(row['confident_wrong'] for row in r):5d} "
            f"{speed:10.1f}"
        )
    for row in rows:
        if not row["success"]:
            print(f"  failed: {row['name']} seed {row['seed']}: {row['reason']}")


if __name__ == "__main__":
    main()
