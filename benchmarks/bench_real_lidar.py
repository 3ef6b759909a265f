"""Real laser logs against their own maps: does ``bim-init match`` place a real robot by its lidar
alone, and never wrongly?

Each CARMEN log of ``../shared/real_lidar`` (real buildings, furniture, people and glass, sparse
corrected scans) gives two sites (``bim-extract MAP.yaml``): the whole log's occupancy map and a
walls-only map (the long straight structures, as a BIM draws walls, while the scans still see
everything else; :mod:`_real_lidar`). Windows of ``--window`` m from starts spread over the log,
their odometry drifting (scale and turn errors of 2 % sd, a heading random walk), are matched as
``bim-init match WINDOW.jsonl --site SITE`` matches them (the camera absent: the lidar registration
replayed along the window, the first unique one that passes the checks claimed). The claimed pose
at the window's last odometry stamp is scored against the truth:

* **right**: unique within ``--right-m`` m and ``--right-deg`` degrees;
* **confident-wrong**: unique and off by more than ``--wrong-m`` m or ``--wrong-deg`` degrees
  (``bim-init eval``'s failure rule); in between: imprecise;
* **undecided**: no unique claim (an honest failure).

Beside it, AMCL's global localisation (5000 particles, the paper's baseline) on the same windows,
the same drifted odometry and the same map: right when it converges (the fine-tuning covariance
thresholds) within 0.5 m and 5 degrees. The table and ``--out`` JSON feed the docs' results page.

    python benchmarks/bench_real_lidar.py [--quick] [--logs DIR] [--windows N] [--out FILE.json]

Skips (exit 0, a line) where ``../shared/real_lidar`` is absent (a bare clone).
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
from _real_lidar import (
    DRIFT,
    LogTruth,
    log_truth,
    walls_only,
    whole_log_map,
    window_records,
    windows,
    write_site,
)

from initcli.core.geometry.se2 import Pose2D

REAL_LIDAR = ROOT.parent / "shared" / "real_lidar"
ATTEMPTS: list[dict[str, Any]] = []  # every registration along the windows (--attempts)


def match_window(records: list[Any], site: Path, workdir: Path) -> tuple[Any, float]:
    """``bim-init match`` on the window: the report (the claim first) and its seconds."""
    from initcli.core.lidar.registration_params import RegistrationParams
    from initcli.io.log_writer import write_log
    from initcli.match.pipeline import run_match
    from initcli.verify.registration import check_and_register

    log = workdir / "window.jsonl"
    write_log(log, records)
    started = time.perf_counter()
    report = run_match(log, site)
    check_and_register(log, site, report, False, report.options.top, RegistrationParams())
    return report, time.perf_counter() - started


def amcl_window(records: list[Any], grid: Any, seed: int) -> tuple[Any, float | None, float]:
    """AMCL global localisation along the window: its pose when it converged (None: never), the
    time of the odometry record then, and its seconds."""
    from initcli.baselines.amcl import MIN_TRAVEL
    from initcli.config import SessionConfig
    from initcli.core.filters.global_localisation import GlobalLocalisation, GlobalLocalisationParams
    from initcli.core.geometry.motion import motion_delta
    from initcli.core.geometry.se2 import Pose2D
    from initcli.io.log_records import Odom, Scan

    started = time.perf_counter()
    thresholds = SessionConfig().fine_tuning
    amcl = GlobalLocalisation(grid, GlobalLocalisationParams(), np.random.default_rng(seed))
    odom: Pose2D | None = None
    odom_t = 0.0
    last: Pose2D | None = None
    travelled, converged_at = 0.0, None
    for record in records:
        if isinstance(record, Odom):
            pose = Pose2D(record.x, record.y, record.yaw)
            travelled += 0.0 if odom is None else odom.distance_to(pose)
            odom, odom_t = pose, record.t
        elif isinstance(record, Scan) and odom is not None:
            angles = record.angle_min + record.angle_increment * np.arange(len(record.ranges))
            ranges = np.array(record.ranges, dtype=float)
            if last is None:
                amcl.update(angles, ranges, record.range_max)
                last = odom
                continue
            moved = motion_delta(last, odom)
            if not amcl.moved_enough(moved):
                continue
            amcl.predict(moved)
            amcl.update(angles, ranges, record.range_max)
            last = odom
            cov = amcl.whole_covariance()
            if (
                travelled >= MIN_TRAVEL
                and cov[0, 0] < thresholds.covariance
                and cov[1, 1] < thresholds.covariance
                and cov[2, 2] < thresholds.yaw_covariance
            ):
                converged_at = (amcl.estimate().pose, odom_t)
                break
    seconds = time.perf_counter() - started
    if converged_at is None:
        return None, None, seconds
    return converged_at[0], converged_at[1], seconds


def attempts(
    records: list[Any], site: Path, workdir: Path, truth: LogTruth, wall_lines: float
) -> list[dict[str, Any]]:
    """Every registration a session would make along the window (every ``registration.every`` m),
    unique or not: the best place's fit, the best distinct place's fit, and whether the best place
    is the truth (within 0.5 m and 5 degrees) -- what the thresholds min_fit and margin are judged
    by."""
    from dataclasses import replace

    from bimtools.site.load import load_site
    from initcli.core.geometry.se2 import Pose2D
    from initcli.core.lidar.registration_params import RegistrationParams
    from initcli.core.verify.params import VerificationParams
    from initcli.io.detection_log import read_log
    from initcli.io.log_writer import write_log
    from initcli.verify.evidence import PathEvidence
    from initcli.verify.registration import SubmapRegistration

    log_path = workdir / "attempts.jsonl"
    write_log(log_path, records)
    log = read_log(log_path)
    params = replace(RegistrationParams(), wall_lines=wall_lines)
    registration = SubmapRegistration(params, load_site(site), None, VerificationParams().scan_tolerance)
    true_at = {o.t: Pose2D(o.x, o.y, o.yaw) for o in truth.odom}
    found = []
    for path, travel, t in PathEvidence.growing(log):
        if not registration.due(travel):
            continue
        result, last = registration.attempt(path, travel)
        best = result.best
        if best is None or last is None or t not in true_at:
            continue
        # the robot's pose at the submap's last scan, in the map: the registration's best pose
        odom_now = [o for o in records if getattr(o, "t", None) == t and hasattr(o, "yaw")][0]
        now = Pose2D(odom_now.x, odom_now.y, odom_now.yaw)
        claimed = best.pose * (last.inverse() * now)
        off_m, off_deg = claimed.distance_to(true_at[t]), math.degrees(claimed.yaw_error(true_at[t]))
        rival = result.rival
        found.append(
            {
                "fit": best.fit,
                "rival": 0.0 if rival is None else rival.fit,
                "right": off_m <= 0.5 and off_deg <= 5,
                "wrong": off_m > 2.0 or off_deg > 30.0,
            }
        )
    return found


def threshold_table(found: list[dict[str, Any]]) -> list[str]:
    """The best places that each (min_fit, margin) pair would claim: right (0.5 m, 5 degrees) /
    imprecise / wrong (over 2 m or 30 degrees off, ``bim-init eval``'s failure rule)."""
    lines = [
        "| min_fit \\ margin | " + " | ".join(f"{m:.2f}" for m in MARGINS) + " |",
        "|---" * (len(MARGINS) + 1) + "|",
    ]
    for fit in MIN_FITS:
        cells = []
        for margin in MARGINS:
            claimed = [a for a in found if a["fit"] >= fit and a["fit"] - a["rival"] >= margin]
            right, wrong = sum(a["right"] for a in claimed), sum(a.get("wrong", False) for a in claimed)
            cells.append(f"{right} / {len(claimed) - right - wrong} / {wrong}")
        lines.append(f"| {fit:.2f} | " + " | ".join(cells) + " |")
    return lines


MIN_FITS = (0.6, 0.65, 0.7, 0.75, 0.8, 0.85)
MARGINS = (0.05, 0.1, 0.15, 0.2, 0.25)


def score(pose: Any, truth: Any, args: argparse.Namespace) -> str:
    if pose is None:
        return "undecided"
    off_m = pose.distance_to(truth)
    off_deg = math.degrees(pose.yaw_error(truth))
    if off_m <= args.right_m and off_deg <= args.right_deg:
        return "right"
    if off_m > args.wrong_m or off_deg > args.wrong_deg:
        return "wrong"
    return "imprecise"


def claim_pose(report: Any, records: list[Any], truth: LogTruth) -> tuple[Any, Any, float | None]:
    """The claim where it was made: (its pose, the true pose then, m of travel to it). A claim of
    Algorithm 1 or at the log's end is judged at the last odometry stamp."""
    from initcli.core.geometry.se2 import Pose2D
    from initcli.io.log_records import Odom

    top = report.hypotheses[0]
    registration = report.registration
    odom = [r for r in records if isinstance(r, Odom)]
    at = odom[-1]
    travel = None
    if registration is not None and registration.t is not None:
        at = min(odom, key=lambda o: abs(o.t - registration.t))
        travel = registration.travel
    claimed = top.transform * Pose2D(at.x, at.y, at.yaw)
    true = next(o for o in truth.odom if o.t == at.t)
    return claimed, Pose2D(true.x, true.y, true.yaw), travel


def run_log(path: Path, args: argparse.Namespace, workdir: Path) -> list[dict[str, Any]]:
    truth: LogTruth = log_truth(path)
    name = path.name.split(".")[0].replace("-corrected", "")
    whole = whole_log_map(truth)
    grids = {"whole-log": whole, "walls-only": walls_only(whole)}
    rows = []
    for kind, grid in grids.items():
        if kind not in args.maps:
            continue
        site = write_site(grid, f"{name}_{kind.replace('-', '_')}", workdir)
        for k, (first, last) in enumerate(windows(truth, args.window, args.windows)):
            rng = np.random.default_rng(args.seed + k)
            records, true_pose = window_records(truth, first, last, DRIFT, rng)
            if args.attempts:
                found = attempts(records, site, workdir, truth, args.wall_lines)
                for a in found:
                    a.update(log=name, map=kind)
                ATTEMPTS.extend(found)
            report, seconds = match_window(records, site, workdir)
            unique = bool(report.hypotheses) and report.outcome == "unique match"
            claimed, then, travel = claim_pose(report, records, truth) if unique else (None, None, None)
            outcome = score(claimed, then, args)
            row: dict[str, Any] = {
                "log": name,
                "map": kind,
                "window": [first, last],
                "outcome": outcome,
                "decided_by": report.decided_by if unique else None,
                "travel_to_claim_m": None if travel is None else round(travel, 1),
                "seconds": round(seconds, 2),
                "error_m": None if claimed is None else round(claimed.distance_to(then), 3),
                "error_at_end_m": None
                if not unique
                else round(report.hypotheses[0].pose.distance_to(true_pose), 3),
            }
            if args.amcl:
                pose, at, amcl_seconds = amcl_window(records, grid, args.seed + k)
                then_amcl = None if at is None else next(o for o in truth.odom if o.t == at)
                row["amcl"] = score(
                    pose, None if then_amcl is None else Pose2D(then_amcl.x, then_amcl.y, then_amcl.yaw), args
                )
                row["amcl_seconds"] = round(amcl_seconds, 2)
            rows.append(row)
            print(
                f"  {name:10s} {kind:10s} window {first:4d}-{last:4d}: {outcome:9s}"
                f" {row['decided_by'] or '-':20s} {seconds:5.1f} s"
                + (f"  amcl {row['amcl']}" if args.amcl else ""),
                flush=True,
            )
    return rows


def summary(rows: list[dict[str, Any]], amcl: bool) -> list[str]:
    lines = [
        "| log | map | windows | right | confident-wrong | imprecise | undecided | m to claim"
        + " | s per window |"
        + (" AMCL right | AMCL wrong |" if amcl else ""),
        "|---|---|---|---|---|---|---|---|---|" + ("---|---|" if amcl else ""),
    ]
    keys = sorted({(r["log"], r["map"]) for r in rows}) + [("all", "whole-log"), ("all", "walls-only")]
    for log, kind in keys:
        mine = [r for r in rows if r["map"] == kind and (log == "all" or r["log"] == log)]
        if not mine:
            continue
        n = len(mine)

        def count(outcome: str, field: str = "outcome", rows_: list[dict[str, Any]] = mine) -> int:
            return sum(r.get(field) == outcome for r in rows_)

        travel = [r["travel_to_claim_m"] for r in mine if r["travel_to_claim_m"] is not None]
        line = (
            f"| {log} | {kind} | {n} | {count('right')} ({100 * count('right') / n:.0f} %) | {count('wrong')}"
            f" | {count('imprecise')} | {count('undecided')}"
            f" | {np.mean(travel):.1f} | {np.mean([r['seconds'] for r in mine]):.1f} |"
            if travel
            else f"| {log} | {kind} | {n} | {count('right')} (0 %) | {count('wrong')} | {count('imprecise')}"
            f" | {count('undecided')} | - | {np.mean([r['seconds'] for r in mine]):.1f} |"
        )
        if amcl:
            amcl_right = count("right", "amcl")
            line += f" {amcl_right} ({100 * amcl_right / n:.0f} %) | {count('wrong', 'amcl')} |"
        lines.append(line)
    return lines


def provenance(args: argparse.Namespace) -> dict[str, Any]:
    """What the docs page says of the run: the command, the commit, the machine, the rules."""
    import os
    import subprocess
    import sys

    commit = subprocess.run(
        ["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=False
    ).stdout.strip()
    return {
        "command": "python benchmarks/bench_real_lidar.py " + " ".join(sys.argv[1:]),
        "commit": commit,
        "machine": f"{os.cpu_count()} CPU cores",
        "logs": sorted({str(p.name) for p in args.logs.glob("*.log.gz")}),
        "window_m": args.window,
        "right_m": args.right_m,
        "right_deg": args.right_deg,
        "wrong_m": args.wrong_m,
        "wrong_deg": args.wrong_deg,
        "drift": {"scale_sd": DRIFT.scale_sd, "turn_sd": DRIFT.turn_sd, "heading_per_m": DRIFT.heading_per_m},
    }


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--logs", type=Path, default=REAL_LIDAR, help="folder of CARMEN logs (*.log.gz)")
    parser.add_argument("--only", default="", help="comma-separated log names (intel, aces, ...)")
    parser.add_argument("--windows", type=int, default=10, help="windows per log and map")
    parser.add_argument("--window", type=float, default=60.0, help="m of travel per window")
    parser.add_argument("--maps", default="whole-log,walls-only")
    parser.add_argument("--amcl", action=argparse.BooleanOptionalAction, default=True)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--right-m", type=float, default=0.5)
    parser.add_argument("--right-deg", type=float, default=5.0)
    parser.add_argument("--wrong-m", type=float, default=2.0)
    parser.add_argument("--wrong-deg", type=float, default=30.0)
    parser.add_argument(
        "--attempts",
        action="store_true",
        help="also every registration along each window: the thresholds' table",
    )
    parser.add_argument(
        "--wall-lines", type=float, default=1.0, help="registration.wall_lines for --attempts"
    )
    parser.add_argument("--out", type=Path, default=None, help="write the rows as JSON here")
    args = parse_args(parser, {"only": "intel", "windows": 2, "amcl": False})
    if not args.logs.is_dir():
        print(
            f"bench_real_lidar: skipped: no folder {args.logs} (the real laser logs are not in a bare clone)"
        )
        return 0
    only = {s for s in args.only.split(",") if s}
    logs = [
        p for p in sorted(args.logs.glob("*.log.gz")) if not only or any(p.name.startswith(o) for o in only)
    ]
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for path in logs:
            print(f"{path.name}:", flush=True)
            rows += run_log(path, args, Path(tmp))
    print("\n".join(summary(rows, args.amcl)))
    if args.attempts:
        for kind in ("whole-log", "walls-only"):
            mine = [a for a in ATTEMPTS if a["map"] == kind]
            print(f"\nregistrations along the windows, {kind} maps: right / imprecise / wrong places claimed")
            print("\n".join(threshold_table(mine)))
    wrong = sum(r["outcome"] == "wrong" for r in rows)
    print(f"confident-wrong claims: {wrong}")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        doc: dict[str, Any] = {"provenance": provenance(args), "rows": rows}
        if args.attempts:
            doc["thresholds"] = {
                kind: threshold_table([a for a in ATTEMPTS if a["map"] == kind])
                for kind in ("whole-log", "walls-only")
            }
        args.out.write_text(json.dumps(doc, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
