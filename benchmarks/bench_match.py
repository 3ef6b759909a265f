"""Benchmark of ``bim-init match`` (a benchmark, not a timed test). Runs on one core.

Sections (``--only`` picks some):

- ``incremental``: one more detected feature added to an existing hypothesis set (``Matcher.extend``)
  on synthetic floors of 100, 1,000 and 10,000 features. Goals: <= 5 ms at 1,000, <= 50 ms at 10,000.
- ``oracle``: the indexed matcher against the plain transcription of Algorithm 1 kept in
  ``benchmarks/_oracle.py`` (the tests' oracle too) -- same matches on random cases, and the speed
  ratio.
- ``pipeline``: the whole log-to-verdict time (read the log, Eq. 1-2, filter, match, poses, verdict).
- ``accuracy``: paper (Eq. 10-13) vs rigid (Kabsch) pose error on noisy synthetic logs over the
  sample models (``sample_models/*.ifc`` through ``bim-extract``) and synthetic floors.
- ``outliers``: the measured effect of ``--max-outliers`` 0 vs 1 on clean logs and on logs with one
  persistent false detection (a poster that looks like a door).

Usage: ``.venv/bin/python benchmarks/bench_match.py [--quick] [--only incremental,oracle,...]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import math  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import zlib  # noqa: E402
from collections import Counter  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _common import SAMPLES, parse_args  # noqa: E402
from _oracle import algorithm1, algorithm1_with_outliers  # noqa: E402

from bimtools.site.load import Site, load_site  # noqa: E402
from initcli.core.geometry.se2 import Pose2D  # noqa: E402
from initcli.core.hypotheses.matching import BimIndex, Matcher  # noqa: E402
from initcli.core.hypotheses.ranking import Verdict  # noqa: E402
from initcli.io.detection_log import read_log  # noqa: E402
from initcli.io.log_writer import write_log  # noqa: E402
from initcli.match.pipeline import MatchOptions, match_log, site_class_map  # noqa: E402
from initcli.sim.synthetic_floor import SyntheticFloor, doors_along, make_floor, write_site_folder  # noqa: E402
from initcli.sim.synthetic_log import (  # noqa: E402
    SimFeature,
    SyntheticParams,
    make_log,
    path_from_waypoints,
    sim_features_from_bim,
)
from initcli.sim.synthetic_paths import random_path  # noqa: E402

# Realistic noise for the accuracy and outlier sections: RGB-D depth error growing with the
# square of the range, box jitter, boxes clipped at the image border, odometry drift, missed
# detections and random non-persistent false boxes.
NOISY = SyntheticParams(
    depth_noise=0.02,
    depth_noise_quad=0.008,
    pixel_noise=4.0,
    clip_boxes=True,
    odom_noise=(0.02, 0.05),
    detect_probability=0.7,
    false_positive_rate=0.05,
)


def pin_one_core() -> str:
    try:
        cpu = min(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpu})
        return f"pinned to CPU {cpu}"
    except (AttributeError, OSError):
        return "not pinned (no sched_setaffinity)"


def corridor_sequence(
    floor: SyntheticFloor, rng: np.random.Generator, n: int, noise: float
) -> tuple[np.ndarray, list[str]]:
    """n features seen in walking order along a random corridor, in a random odom frame with noise."""
    while True:
        k = int(rng.integers(floor.corridors))
        x0 = float(rng.uniform(0, floor.length))
        x1 = x0 + (1 if rng.random() < 0.5 else -1) * floor.length
        seq = doors_along(floor, k, x0, x1)[:n]
        if len(seq) == n:
            break
    to_odom = Pose2D(*rng.uniform(-100, 100, 2), rng.uniform(-math.pi, math.pi))
    xy = to_odom.apply(floor.xy[seq]) + rng.normal(0, noise, (n, 2))
    return xy, [floor.classes[i] for i in seq]


def section_incremental(quick: bool) -> None:
    print("\n## incremental update: Matcher.extend, one more feature (ms per update, one core)")
    print(
        "alpha 0.5 m, beta 15 deg, feature noise 0.1 m; columns: features already matched -> time (partials)"
    )
    sizes = (100, 1000) if quick else (100, 1000, 10000)
    reps = 3 if quick else 8
    for n_feat in sizes:
        floor = make_floor(n_feat, seed=1)
        index = BimIndex(floor.xy, floor.classes)
        rng = np.random.default_rng(7)
        for max_out in (0, 1):
            matcher = Matcher(index, MatchOptions(max_outliers=max_out, revisits=False).match_params())
            times: dict[int, list[float]] = {n: [] for n in range(3, 10)}
            parts: dict[int, list[int]] = {n: [] for n in range(3, 10)}
            for _ in range(reps):
                xy, cls = corridor_sequence(floor, rng, 9, 0.1)
                state = matcher.match(xy[:2], cls[:2])
                for n in range(3, 10):
                    t0 = time.perf_counter()
                    new = matcher.extend(state, xy[n - 1], cls[n - 1])
                    times[n].append((time.perf_counter() - t0) * 1e3)
                    parts[n].append(len(state))
                    state = new
            cells = " ".join(
                f"{n - 1}->{np.median(times[n]):.2f}({int(np.median(parts[n]))})" for n in range(3, 10)
            )
            typical = np.median([t for n in range(4, 10) for t in times[n]])
            worst = max(t for n in range(3, 10) for t in times[n])
            print(
                f"{len(floor.features):6d} features  max_outliers={max_out}: median {typical:6.2f} ms "
                f"(adding the 4th..9th), worst {worst:6.2f} ms | {cells}"
            )


def section_oracle(quick: bool) -> None:
    print("\n## oracle: plain Algorithm 1 (benchmarks/_oracle.py) vs the indexed matcher, whole sequence")
    for n_feat in (100, 1000) if not quick else (100,):
        floor = make_floor(n_feat, seed=3)
        index = BimIndex(floor.xy, floor.classes)
        rng = np.random.default_rng(11)
        for max_out in (0, 1):
            params = MatchOptions(max_outliers=max_out, min_inliers=3, revisits=False).match_params()
            t_plain = t_fast = 0.0
            same = 0
            cases = 3 if (n_feat >= 1000 and max_out) else 5
            n_s = 4 if max_out else 6
            for _ in range(cases):
                xy, cls = corridor_sequence(floor, rng, n_s, 0.1)
                t0 = time.perf_counter()
                if max_out:
                    plain = algorithm1_with_outliers(
                        floor.xy.tolist(),
                        floor.classes,
                        xy.tolist(),
                        cls,
                        params.alpha,
                        params.beta,
                        max_out,
                        3,
                    )
                else:
                    plain = set(
                        algorithm1(
                            floor.xy.tolist(), floor.classes, xy.tolist(), cls, params.alpha, params.beta
                        )
                    )
                t_plain += time.perf_counter() - t0
                t0 = time.perf_counter()
                state = Matcher(index, params).match(xy, cls)
                rows = state.matches(params)
                fast = {tuple(int(a) for a in r) for r in state.assign[rows]}
                t_fast += time.perf_counter() - t0
                same += fast == plain
            print(
                f"{len(floor.features):6d} features, {n_s} detected, max_outliers={max_out}: same matches in "
                f"{same}/{cases} cases; plain {t_plain / cases * 1e3:9.1f} ms, "
                f"indexed {t_fast / cases * 1e3:7.2f} ms, "
                f"speed-up x{t_plain / max(t_fast, 1e-9):.0f}"
            )


def floor_site(floor: SyntheticFloor, folder: Path) -> Path:
    return write_site_folder(folder, {"L1": (floor.features, floor.walls)})


def section_pipeline(quick: bool, tmp: Path) -> None:
    print("\n## log to verdict: read log + Eq. 1-2 + filter + Algorithm 1 + poses + verdict (one core)")
    for n_feat in (100, 1000) if quick else (100, 1000, 10000):
        floor = make_floor(n_feat, seed=5)
        site_dir = floor_site(floor, tmp / f"floor{n_feat}")
        t0 = time.perf_counter()
        site = load_site(site_dir, with_maps=False)
        t_site = time.perf_counter() - t0
        k = floor.corridors // 2
        y = floor.corridor_y(k)
        t, path = path_from_waypoints([(5.0, y), (30.0, y)])
        log = make_log(floor.features, t, path, walls=floor.walls[:, :4], seed=1)
        log_path = tmp / f"floor{n_feat}.jsonl"
        write_log(log_path, log.records)
        runs = []
        for _ in range(3):
            t0 = time.perf_counter()
            report = match_log(read_log(log_path), site, MatchOptions(), site_class_map(site))
            runs.append(time.perf_counter() - t0)
        n_records = len(log.records)
        print(
            f"{len(floor.features):6d} features, log of {n_records} records, "
            f"{len(report.features)} confirmed: "
            f"{min(runs) * 1e3:7.1f} ms log-to-verdict ({report.verdict}); site loading {t_site * 1e3:.0f} ms"
        )


def sample_sites(tmp: Path, extra: list[Path]) -> dict[str, Site]:
    sites: dict[str, Site] = {}
    exe = Path(sys.executable).with_name("bim-extract")
    for ifc in sorted(SAMPLES.glob("*.ifc")):
        out = tmp / ifc.stem
        cmd = [str(exe) if exe.exists() else "bim-extract", str(ifc), "-o", str(out)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"{ifc}: bim-extract failed (exit {done.returncode}): {done.stderr[-500:]}")
        sites[ifc.stem] = load_site(out)
    for folder in extra:
        sites[folder.name] = load_site(folder)
    return sites


def sample_logs(site: Site, n: int, seed: int, tmp: Path, phantom: bool = False):
    """Noisy logs along random paths through the first storey; optionally one persistent phantom door
    (placed on a wall the robot looks at, and kept only if it is rendered in at least 3 images)."""
    storey = next(iter(site.storeys.values()))
    feats = sim_features_from_bim(storey.features)
    walls = np.array([[w.x1, w.y1, w.x2, w.y2] for w in storey.walls]).reshape(-1, 4)
    fronts = np.array([[f.x + f.norm_x, f.y + f.norm_y] for f in feats])
    rng = np.random.default_rng(seed)
    out = []
    for trial in range(n):
        for _attempt in range(20):
            try:
                waypoints = random_path(storey.grid, rng, 10.0, 35.0, near=fronts)
            except ValueError:
                continue
            t, path = path_from_waypoints(waypoints)
            phantoms: list[SimFeature] = []
            if phantom:
                ghost = _phantom_in_view(storey.walls, path, feats, rng)
                if ghost is None:
                    continue
                phantoms = [ghost]
            log = make_log(
                feats, t, path, params=NOISY, walls=walls, phantoms=phantoms, seed=seed * 1000 + trial
            )
            if phantom:
                seen = sum(
                    1
                    for r in log.records
                    if getattr(r, "objects", None) and _has_phantom(r, phantoms[0], log)
                )
                if seen < 3:
                    continue
            p = tmp / f"s{seed}_{trial}.jsonl"
            write_log(p, log.records)
            out.append((read_log(p), log.final_pose, log))
            break
    return out


def _has_phantom(record, ghost: SimFeature, log) -> bool:
    """Does this detections record hold a box of the phantom (its centre maps onto the phantom)?"""
    from initcli.core.geometry.projection import detections_to_odom

    meta = log.records[0]
    boxes = np.array([o.bbox for o in record.objects])
    depth = np.array([o.depth for o in record.objects])
    pts = log.start_pose.apply(
        detections_to_odom(boxes, depth, meta.camera, meta.camera_pose, record.pose)[:, :2]
    )
    return bool(np.any(np.hypot(pts[:, 0] - ghost.x, pts[:, 1] - ghost.y) < 0.5))


def _phantom_in_view(
    walls, path: np.ndarray, feats: list[SimFeature], rng: np.random.Generator
) -> SimFeature | None:
    """A 'door' where a ray from the middle part of the path, roughly ahead, meets a wall 2-5 m away,
    at least 1.5 m from every real feature."""
    real = np.array([[f.x, f.y] for f in feats])
    seg = np.array([[w.x1, w.y1, w.x2, w.y2] for w in walls])
    normals = np.array([w.normal for w in walls])
    for _ in range(60):
        x, y, yaw = path[int(rng.integers(len(path) // 4, max(len(path) // 4 + 1, 3 * len(path) // 4)))]
        ang = yaw + rng.uniform(-0.35, 0.35)
        d = np.array([math.cos(ang), math.sin(ang)])
        p = np.array([x, y])
        a, b = seg[:, :2], seg[:, 2:]
        e = b - a
        den = d[0] * e[:, 1] - d[1] * e[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((a[:, 0] - p[0]) * e[:, 1] - (a[:, 1] - p[1]) * e[:, 0]) / den
            u = ((a[:, 0] - p[0]) * d[1] - (a[:, 1] - p[1]) * d[0]) / den
        ok = np.isfinite(t) & (t > 0) & (u >= 0.05) & (u <= 0.95)
        if not ok.any():
            continue
        k = int(np.flatnonzero(ok)[np.argmin(t[ok])])
        if not 2.0 <= t[k] <= 5.0:
            continue
        hit = p + t[k] * d
        if np.min(np.hypot(*(real - hit).T)) < 1.5:
            continue
        n = normals[k] if np.dot(normals[k], p - hit) > 0 else -normals[k]
        return SimFeature("phantom", "door", float(hit[0]), float(hit[1]), float(n[0]), float(n[1]))
    return None


def _errors(pose: Pose2D, truth: Pose2D) -> tuple[float, float]:
    return pose.distance_to(truth), math.degrees(pose.yaw_error(truth))


def section_accuracy(quick: bool, tmp: Path, extra: list[Path]) -> None:
    print(
        "\n## pose accuracy: paper (Eq. 10-13) vs rigid (Kabsch), noisy synthetic logs, "
        "unique correct matches"
    )
    print(f"noise: {NOISY}")
    sites = sample_sites(tmp / "sites", extra)
    n = 6 if quick else 40
    totals: dict[str, list[tuple[float, float, float, float]]] = {"paper": [], "rigid": []}
    for name, site in sites.items():
        rows: dict[str, list[tuple[float, float, float, float]]] = {"paper": [], "rigid": []}
        logs = sample_logs(site, n, seed=zlib.crc32(name.encode()) % 1000, tmp=tmp)
        for log, truth, _ in logs:
            reports = {
                m: match_log(log, site, MatchOptions(pose_method=m), site_class_map(site))
                for m in ("paper", "rigid")
            }
            if any(r.outcome is not Verdict.UNIQUE for r in reports.values()):
                continue
            if reports["rigid"].hypotheses[0].pose.distance_to(truth) > 2.0:
                continue
            for m, r in reports.items():
                h = r.hypotheses[0]
                rect = h.reported_pose
                rows[m].append((*_errors(h.pose, truth), *_errors(rect, truth)))
        for m in ("paper", "rigid"):
            totals[m].extend(rows[m])
            _print_errors(f"{name} ({len(logs)} logs)", m, rows[m])
    for m in ("paper", "rigid"):
        _print_errors("ALL samples", m, totals[m])
    means = {m: np.mean([r[0] for r in totals[m]]) if totals[m] else math.inf for m in totals}
    print(f"more accurate on the samples (mean position error): {min(means, key=means.__getitem__)}")


def _print_errors(name: str, method: str, rows: list[tuple[float, float, float, float]]) -> None:
    if not rows:
        print(f"  {name:28s} {method:5s}: no unique correct match")
        return
    a = np.array(rows)
    print(
        f"  {name:28s} {method:5s}: n={len(a):3d} position mean {a[:, 0].mean():.3f} m "
        f"median {np.median(a[:, 0]):.3f} p90 {np.percentile(a[:, 0], 90):.3f} | heading mean "
        f"{a[:, 1].mean():.2f} deg p90 {np.percentile(a[:, 1], 90):.2f}"
        f" | rectified: {a[:, 2].mean():.3f} m {a[:, 3].mean():.2f} deg"
    )


def section_outliers(quick: bool, tmp: Path, extra: list[Path]) -> None:
    print("\n## outlier tolerance: --max-outliers 0 (the paper) vs 1, on the samples")
    print(
        "outcome of each log: unique-correct, unique-WRONG, ambiguous with/without the truth among the "
        "hypotheses, no match"
    )
    sites = sample_sites(tmp / "sites_o", extra)
    n = 5 if quick else 30
    for phantom in (False, True):
        label = "one persistent false door" if phantom else "clean (random non-persistent false boxes only)"
        tallies = {0: Counter(), 1: Counter()}
        for name, site in sites.items():
            for log, truth, _ in sample_logs(
                site, n, seed=500 + zlib.crc32(name.encode()) % 1000, tmp=tmp, phantom=phantom
            ):
                for k in (0, 1):
                    r = match_log(log, site, MatchOptions(max_outliers=k, top=100_000), site_class_map(site))
                    has = any(h.pose.distance_to(truth) < 1.5 for h in r.hypotheses)
                    if r.outcome is Verdict.UNIQUE:
                        tallies[k]["unique-correct" if has else "unique-WRONG"] += 1
                    elif r.outcome is Verdict.AMBIGUOUS:
                        tallies[k]["ambiguous+truth" if has else "ambiguous-truth"] += 1
                    else:
                        tallies[k]["no match"] += 1
        print(f"  {label}:")
        for k in (0, 1):
            t = tallies[k]
            total = sum(t.values())
            keys = ("unique-correct", "unique-WRONG", "ambiguous+truth", "ambiguous-truth", "no match")
            print(f"    max_outliers={k}: " + ", ".join(f"{key} {t[key]}/{total}" for key in keys))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="incremental,oracle,pipeline,accuracy,outliers")
    parser.add_argument(
        "--site", action="append", type=Path, default=[], help="extra site folder for accuracy"
    )
    args = parse_args(parser, quick={})  # --quick: smaller sizes and fewer logs in every section
    print(f"bench_match: {pin_one_core()}; python {sys.version.split()[0]}, numpy {np.__version__}")
    only = set(args.only.split(","))
    with tempfile.TemporaryDirectory(prefix="bench_match.") as tmpdir:
        tmp = Path(tmpdir)
        if "incremental" in only:
            section_incremental(args.quick)
        if "oracle" in only:
            section_oracle(args.quick)
        if "pipeline" in only:
            section_pipeline(args.quick, tmp)
        if "accuracy" in only:
            section_accuracy(args.quick, tmp, args.site)
        if "outliers" in only:
            section_outliers(args.quick, tmp, args.site)


if __name__ == "__main__":
    main()
