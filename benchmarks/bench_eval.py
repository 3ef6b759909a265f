"""Benchmark ``bim-init eval``: trials per minute on the three samples, and the projected time of
the full 3 sites x 100 starts x 4 methods evaluation (goal: under 20 minutes on 2 cores).

    python benchmarks/bench_eval.py [--quick] [--starts 10] [--workers 2] [--reality ideal|construction]

The reality issue's goal: >= 200 trials/min on 2 cores under ``--reality construction`` too.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import SAMPLES, parse_args


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--starts", type=int, default=10)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--reality", choices=["ideal", "construction"], default="ideal")
    args = parse_args(parser, quick={"starts": 1})
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "eval"
        command = [
            str(Path(sys.executable).parent / "bim-init"),
            "eval",
            "--config",
            str(SAMPLES / "eval.yaml"),
            "--starts",
            str(args.starts),
            "--workers",
            str(args.workers),
            "--out",
            str(out),
            "--reality",
            args.reality,
        ]
        started = time.perf_counter()
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            raise SystemExit(f"bim-init eval failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
        elapsed = time.perf_counter() - started
        rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    per_method: dict[str, list[float]] = {}
    for r in rows:
        per_method.setdefault(r["method"], []).append(r["seconds"])
    rate = 60.0 * len(rows) / elapsed
    print(
        f"{len(rows)} trials in {elapsed:.1f} s (including start-up and IFC extraction) "
        f"on {args.workers} workers, reality {args.reality}"
    )
    print(f"trial rate: {rate:.1f} trials/min")
    for method, seconds in per_method.items():
        print(f"  {method:8s} mean {sum(seconds) / len(seconds):.2f} s per trial (one core)")
    full = 3 * 100 * 4
    print(f"projected 3 x 100 x 4 = {full} trials: {full / rate:.1f} min (goal < 20 min on 2 cores)")


if __name__ == "__main__":
    main()
