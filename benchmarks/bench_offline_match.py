"""How often ``bim-init match`` on a session's log gives the unique answer, and never a wrong one.

Runs simulated sessions (``bim-init run``) on the samples in three realities -- the sample config,
``sim.reality: construction``, and a weak camera (60 % of features missed per image, 6 false boxes
a minute, 10 % wrong class) -- then ``bim-init match --json`` on each whole log and on its first
30 / 50 / 70 / 85 % (a log cut before the session could decide). Prints, for the whole logs and
the cut ones: logs, logs whose top hypothesis is at the truth (2 m, 30 degrees), unique verdicts
among those (the goal: >= 75 %), unique verdicts by Algorithm 1 alone and by the lidar along the
path (``decided_by``), and wrong unique verdicts (the count that must stay 0).

    python benchmarks/bench_offline_match.py [--quick] [--seeds 12] [--first-seed 101] [--workers 2]

The defaults (3 samples x 3 realities x 12 seeds, 540 matches) take about 15 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import yaml
from _common import SAMPLES, parse_args

REALITIES: dict[str, dict[str, Any]] = {
    "sample": {},
    "construction": {"reality": "construction"},
    "weak": {"miss_rate": 0.6, "false_positives_per_minute": 6.0, "confusion_rate": 0.1},
}
CUTS = (0.3, 0.5, 0.7, 0.85)
WRONG_M, WRONG_DEG = 2.0, 30.0
BIN = Path(sys.executable).parent / "bim-init"


def _config(folder: Path, sample: str, reality: str) -> Path:
    doc = yaml.safe_load((SAMPLES / f"{sample}.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / Path(doc["site"]["path"]).name)
    doc.setdefault("sim", {}).update(REALITIES[reality])
    path = folder / f"{sample}_{reality}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def _session(job: tuple[Path, Path, int]) -> Path:
    config, out, seed = job
    cmd = [str(BIN), "run", "--config", str(config), "--out", str(out), "--seed", str(seed), "--quiet"]
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return out


def _right(pose: dict[str, float], truth: dict[str, float]) -> bool:
    turn = math.atan2(math.sin(pose["yaw"] - truth["yaw"]), math.cos(pose["yaw"] - truth["yaw"]))
    return (
        math.hypot(pose["x"] - truth["x"], pose["y"] - truth["y"]) < WRONG_M
        and math.degrees(abs(turn)) < WRONG_DEG
    )


def _match(job: tuple[Path, Path]) -> dict[str, Any] | None:
    log, site = job
    out = subprocess.run(
        [str(BIN), "match", str(log), "--site", str(site), "--json"], capture_output=True, text=True
    )
    if not out.stdout.strip():
        return None
    doc = json.loads(out.stdout)
    hs, truth = doc["hypotheses"], doc["truth"]
    return {
        "top_right": bool(hs and truth and _right(hs[0]["pose"], truth)),
        "unique": doc["exit_code"] == 0,
        "decided_by": doc.get("decided_by"),
    }


def _tally(rows: list[dict[str, Any] | None]) -> str:
    c: Counter[str] = Counter()
    for r in rows:
        c["logs"] += 1
        if r is None:
            c["errors"] += 1
            continue
        c["right"] += r["top_right"]
        c["unique_right"] += r["unique"] and r["top_right"]
        c["wrong"] += r["unique"] and not r["top_right"]
        c["paper"] += r["unique"] and r["decided_by"] == "algorithm 1"
        c["lidar"] += r["unique"] and r["decided_by"] == "lidar along the path"
    share = c["unique_right"] / c["right"] if c["right"] else float("nan")
    return (
        f"{c['logs']} logs, top right {c['right']}, unique {c['unique_right']} of those ({share:.0%};"
        f" Algorithm 1 {c['paper']}, lidar along the path {c['lidar']}), wrong unique {c['wrong']},"
        f" errors {c['errors']}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=12)
    parser.add_argument("--first-seed", type=int, default=101)
    parser.add_argument("--samples", default="block_a,block_b,ntu_hallway")
    parser.add_argument("--realities", default=",".join(REALITIES))
    parser.add_argument("--workers", type=int, default=2)
    args = parse_args(parser, {"seeds": 1, "samples": "block_a", "realities": "sample"})
    with tempfile.TemporaryDirectory(prefix="bench_offline_match_") as tmp:
        work = Path(tmp)
        jobs = []
        for sample in args.samples.split(","):
            for reality in args.realities.split(","):
                config = _config(work, sample, reality)
                for seed in range(args.first_seed, args.first_seed + args.seeds):
                    jobs.append((config, work / f"{sample}_{reality}_{seed}", seed))
        with ThreadPoolExecutor(args.workers) as pool:
            sessions = [s for s in pool.map(_session, jobs) if (s / "session.jsonl").is_file()]
        whole, cut = [], []
        for s in sessions:
            whole.append((s / "session.jsonl", s / "site"))
            lines = (s / "session.jsonl").read_text().splitlines(keepends=True)
            for share in CUTS:
                part = s / f"cut_{int(share * 100)}.jsonl"
                part.write_text("".join(lines[: int(len(lines) * share)]))
                cut.append((part, s / "site"))
        with ThreadPoolExecutor(args.workers) as pool:
            print(f"{len(sessions)} sessions of {len(jobs)}")
            print("whole logs:", _tally(list(pool.map(_match, whole))), flush=True)
            print("cut logs:  ", _tally(list(pool.map(_match, cut))), flush=True)


if __name__ == "__main__":
    main()
