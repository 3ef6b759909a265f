"""Lost and found on real laser logs: does ``bim-init watch`` notice a localiser that lost the robot,
never raise a false alarm, and find the robot again, never wrongly?

Each CARMEN log of ``../shared/real_lidar`` (or ``--logs DIR``) gives two sites, as in
``bench_real_lidar``: the whole log's occupancy map and a walls-only map (a building model's
walls). On each, ``--kidnaps`` kidnaps are spliced from two stretches of the log (``--before`` m,
then ``--after`` m elsewhere; the localiser carried on by odometry from the first stretch while the
scans come from the second, :mod:`_watch_splice`), and ``--controls`` stretches of ``--control-m``
m keep the localiser right. Each is replayed as ``bim-init watch LOG --site SITE --json`` replays
it, and scored:

* **false alarm**: a ``lost`` event on a control, or before a kidnap's splice;
* **detected**: a ``lost`` event within ``--detect-m`` m of travel after the splice;
* **recovered**: a ``recovered`` pose within ``--right-m`` m and ``--right-deg`` degrees of the
  truth then; **wrong**: one off by more than ``--wrong-m`` m or ``--wrong-deg`` degrees.

Goals (issue 49): zero false alarms, >= 90 % detected within 15 m, >= 70 % recovered, zero wrong.

    python benchmarks/bench_watch.py [--quick] [--logs DIR] [--kidnaps N] [--controls N] [--out FILE.json]

Skips (exit 0, a line) where the logs are absent (a bare clone).
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from _common import ROOT, parse_args
from _real_lidar import LogTruth, log_truth, walls_only, whole_log_map, write_site
from _watch_splice import Case, control, kidnap, stretch

REAL_LIDAR = ROOT.parent / "shared" / "real_lidar"
MIN_APART_M = 3.0  # m: a kidnap carries the robot at least this far ...
MIN_APART_TRAVEL = 20.0  # m: ... from a part of the log at least this much travel away


def cases(truth: LogTruth, args: argparse.Namespace, rng: np.random.Generator) -> list[Case]:
    """``args.kidnaps`` kidnaps (their first stretches spread over the log) and ``args.controls``
    controls."""
    found: list[Case] = []
    total = float(truth.travel[-1])
    starts = np.linspace(0.0, max(total - args.before - args.after, 0.0), max(args.kidnaps, 1) + 1)[:-1]
    for start in starts[: args.kidnaps]:
        a = stretch(truth, float(start), args.before)
        if a is None:
            continue
        end = truth.scan_poses[a[1]]
        for _ in range(200):  # a second stretch far from where the first ends, in place and travel
            b_start = float(rng.uniform(0.0, max(total - args.after, 0.0)))
            b = stretch(truth, b_start, args.after)
            if b is None or abs(truth.travel[b[0]] - truth.travel[a[1]]) < MIN_APART_TRAVEL:
                continue
            if math.hypot(*(truth.scan_poses[b[0]][:2] - end[:2])) >= MIN_APART_M:
                found.append(kidnap(truth, a, b, rng))
                break
    for start in np.linspace(0.0, max(total - args.control_m, 0.0), max(args.controls, 1))[: args.controls]:
        a = stretch(truth, float(start), args.control_m)
        if a is not None:
            found.append(control(truth, a, rng))
    return found


def replay(case: Case, site: Path, workdir: Path, name: str = "case") -> tuple[Any, float]:
    """``bim-init watch LOG --site SITE`` on the case (written to ``workdir/NAME.jsonl``): its result
    and seconds."""
    from bimtools.site.load import load_site
    from initcli.io.detection_log import read_log
    from initcli.io.log_writer import write_log
    from initcli.watch.replay import watch_log

    path = workdir / f"{name}.jsonl"
    write_log(path, case.records)
    started = time.perf_counter()
    result = watch_log(read_log(path), load_site(site))
    return result, time.perf_counter() - started


def score(case: Case, result: Any, args: argparse.Namespace) -> dict[str, Any]:
    lost = [e for e in result.events if e.kind == "lost"]
    found = [e for e in result.events if e.kind == "recovered"]
    splice = math.inf if case.splice_t is None else case.splice_t
    row: dict[str, Any] = {
        "kind": case.kind,
        "false_alarms": sum(e.t < splice for e in lost),
        # the largest evidence a right pose piled up (before the splice): the margin to the threshold
        "right_statistic": round(max([c.statistic for c in result.checks if c.t < splice], default=0.0), 3),
        "events": [e.as_dict() for e in result.events],
        "travel": result.travel,
    }
    if case.splice_t is None:
        return row
    after = [e for e in lost if e.t >= splice]
    row["detected_m"] = None if not after else after[0].travel - case.splice_travel
    row["detected"] = bool(after) and row["detected_m"] <= args.detect_m
    later = [e for e in found if after and e.t >= after[0].t]
    row["recovery"] = "none"
    if later:
        e = later[0]
        truth = case.truth_at(e.t)
        off_m, off_deg = e.pose.distance_to(truth), math.degrees(e.pose.yaw_error(truth))
        row["recovered_m"] = e.travel - case.splice_travel
        row["recovery_error"] = [round(off_m, 3), round(off_deg, 2)]
        if off_m <= args.right_m and off_deg <= args.right_deg:
            row["recovery"] = "right"
        elif off_m > args.wrong_m or off_deg > args.wrong_deg:
            row["recovery"] = "wrong"
        else:
            row["recovery"] = "imprecise"
    return row


def totals(rows: list[dict[str, Any]]) -> dict[str, Any]:
    kidnaps = [r for r in rows if r["kind"] == "kidnap"]
    controls = [r for r in rows if r["kind"] == "control"]
    detected = [r["detected_m"] for r in kidnaps if r["detected"]]
    return {
        "kidnaps": len(kidnaps),
        "controls": len(controls),
        "false_alarms": sum(r["false_alarms"] for r in rows),
        "controls_with_false_alarm": sum(r["false_alarms"] > 0 for r in controls),
        "detected": len(detected),
        "detected_median_m": None if not detected else round(float(np.median(detected)), 2),
        "recovered_right": sum(r["recovery"] == "right" for r in kidnaps),
        "recovered_imprecise": sum(r["recovery"] == "imprecise" for r in kidnaps),
        "recovered_wrong": sum(r["recovery"] == "wrong" for r in kidnaps),
        "right_statistic_max": max((r["right_statistic"] for r in rows), default=0.0),
    }


def provenance(args: argparse.Namespace, logs: list[Path]) -> dict[str, Any]:
    """What the docs page says of the run: the command, the commit, the machine, the rules."""
    import os
    import subprocess
    import sys

    from initcli.core.watch.params import WatchParams

    commit = subprocess.run(
        ["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=False
    ).stdout.strip()
    keys = ("kidnaps", "controls", "before", "after", "control_m", "detect_m", "right_m", "right_deg")
    return {
        "command": "python benchmarks/bench_watch.py " + " ".join(sys.argv[1:]),
        "commit": commit,
        "machine": f"{os.cpu_count()} CPU cores",
        "logs": [p.name for p in logs],
        "threshold": WatchParams().threshold,
        **{k: getattr(args, k) for k in (*keys, "wrong_m", "wrong_deg")},
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--logs", type=Path, default=REAL_LIDAR)
    parser.add_argument("--maps", default="whole,walls", help="whole, walls or both")
    parser.add_argument("--kidnaps", type=int, default=4, help="kidnaps per log and map")
    parser.add_argument("--controls", type=int, default=2, help="controls per log and map")
    parser.add_argument("--before", type=float, default=10.0, help="m driven before the kidnap")
    parser.add_argument("--after", type=float, default=30.0, help="m driven after it")
    parser.add_argument("--control-m", type=float, default=60.0, help="m of a control")
    parser.add_argument("--detect-m", type=float, default=15.0)
    parser.add_argument("--right-m", type=float, default=0.5)
    parser.add_argument("--right-deg", type=float, default=5.0)
    parser.add_argument("--wrong-m", type=float, default=1.0)
    parser.add_argument("--wrong-deg", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=49)
    parser.add_argument("--limit", type=int, default=0, help="logs read at most (0: all)")
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--keep", type=Path, default=None, help="keep the sites and cases' logs here")
    args = parse_args(parser, {"kidnaps": 1, "controls": 1, "limit": 1, "maps": "whole", "control_m": 30.0})
    logs = sorted(args.logs.glob("*.log.gz")) + sorted(args.logs.glob("*.log")) if args.logs.is_dir() else []
    if not logs:
        print(f"bench_watch: no CARMEN logs in {args.logs}: skipped")
        return 0
    logs = logs[: args.limit] if args.limit else logs
    rng = np.random.default_rng(args.seed)
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="bench-watch-") as tmp:
        workdir = args.keep if args.keep is not None else Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        for log in logs:
            truth = log_truth(log)
            whole = whole_log_map(truth)
            grids = {"whole": whole, "walls": walls_only(whole) if "walls" in args.maps else None}
            for name in [m.strip() for m in args.maps.split(",")]:
                site = write_site(grids[name], f"{log.name.split('.')[0]}-{name}", workdir)
                for k, case in enumerate(cases(truth, args, rng)):
                    stem = f"{log.name.split('.')[0]}-{name}-{case.kind}-{k}"
                    result, seconds = replay(case, site, workdir, stem if args.keep else "case")
                    row = {
                        "log": log.name,
                        "map": name,
                        **score(case, result, args),
                        "seconds": round(seconds, 2),
                    }
                    rows.append(row)
                    print(_line(row), flush=True)
    by_map = {m: totals([r for r in rows if r["map"] == m]) for m in sorted({r["map"] for r in rows})}
    for name, t in by_map.items():
        print(
            f"{name}: {t['kidnaps']} kidnaps, {t['controls']} controls: false alarms {t['false_alarms']},"
            f" detected within {args.detect_m:g} m {t['detected']}/{t['kidnaps']} (median"
            f" {t['detected_median_m']} m), recovered right {t['recovered_right']}, imprecise"
            f" {t['recovered_imprecise']}, wrong {t['recovered_wrong']}; a right pose's largest evidence"
            f" {t['right_statistic_max']:.2f}"
        )
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        doc = {"provenance": provenance(args, logs), "totals": by_map, "cases": rows}
        args.out.write_text(json.dumps(doc, indent=1) + "\n")
    return 0


def _line(row: dict[str, Any]) -> str:
    if row["kind"] == "control":
        travel, alarms = f"{row['travel']:5.1f}", row["false_alarms"]
        where = f"{row['log']:28s} {row['map']:5s}"
        return f"{where} control {travel} m: false alarms {alarms} ({row['seconds']} s)"
    det = "-" if row.get("detected_m") is None else f"{row['detected_m']:.1f} m"
    err = row.get("recovery_error", "")
    return (
        f"{row['log']:28s} {row['map']:5s} kidnap: false alarms {row['false_alarms']}, lost after {det},"
        f" recovery {row['recovery']} {err} ({row['seconds']} s)"
    )


if __name__ == "__main__":
    raise SystemExit(main())
