"""Which claim checks matter: every unique match a session considers claiming, right or wrong.

Runs construction sessions (the profile, and twice its door shift and missing doors) on the three
samples and records each claim decision: the claim's own checks (missed predictions, lidar fit,
path), the rivals found with more outliers allowed and whether they pass the same checks, and
whether the claim was right (within 2 m and 30 degrees of the truth). Prints how the decisions
split; for claims held back by rivals the outlier difference to the closest credible rival; and,
for the rule that lets a claim through when every credible rival trails it by
``outrank_outliers`` outliers and ``outrank_scan_fit`` in scan fit (``outranks``), how far the
scan fit of claims at the wrong place beat their credible rivals with that many more outliers:
the margin ``outrank_scan_fit`` must stay above (right claims, for comparison, beat theirs by up
to 0.3).

    python benchmarks/bench_claims.py [--starts 100] [--sweep-starts 20] [--workers 2]

It instruments ``Session._verified`` and ``Session._credible`` (private: this script is a
measurement of the runner, not an API). Takes about 8 minutes on 2 cores with the defaults.
"""

from __future__ import annotations

import argparse
import collections
import math
import multiprocessing
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
SITES = ("block_a", "block_b", "ntu_hallway")
SWEEPS = (("sim.as_built.door_shift", 0.6), ("sim.as_built.missing_doors", 0.4))
WRONG_M, WRONG_DEG = 2.0, 30.0
_SITES: dict[tuple[str, str, float], Any] = {}


def _stats(session: Any, frame: Any, hypothesis: Any, rival: bool) -> dict[str, Any]:
    """Outliers, rightness, checks and scan fit of one hypothesis at ``frame``."""
    truth = frame.truth
    pose = hypothesis.reported_pose
    check = session._verify(hypothesis.storey, pose * frame.odom.inverse(), rival=rival)
    yaw = abs(math.degrees(math.atan2(math.sin(pose.yaw - truth.yaw), math.cos(pose.yaw - truth.yaw))))
    return {
        "outliers": hypothesis.n_outliers,
        "right": math.hypot(pose.x - truth.x, pose.y - truth.y) < WRONG_M and yaw < WRONG_DEG,
        "passed": check.passed,
        "fit": check.scan_fit,
    }


def _session_decisions(job: tuple[str, str, float, int, str]) -> list[dict[str, Any]]:
    from initcli.config import load_config
    from initcli.eval.sweep import apply_sweep, parse_sweep
    from initcli.session import runner
    from initcli.session.setup import prepare_site, sim_session

    name, key, value, seed, work = job
    config = load_config(ROOT / "sample_models" / f"{name}.site.yaml", "construction")
    if key:
        config = apply_sweep(config, parse_sweep(f"{key}={value}"), value)
    if (name, key, value) not in _SITES:  # one extraction per sample and sweep value in each worker
        _SITES[(name, key, value)] = prepare_site(config, Path(work) / f"{name}_{key}_{value}_{seed}")
    site = _SITES[(name, key, value)]
    decisions: list[dict[str, Any]] = []
    seen: dict[str, Any] = {}
    verified, credible = runner.Session._verified, runner.Session._credible

    def spy_credible(self: Any, frame: Any, claim: Any, check: Any, rivals: int, found: list) -> tuple:
        seen["rivals"], seen["found"] = rivals, list(found)
        return credible(self, frame, claim, check, rivals, found)

    def spy_verified(self: Any, frame: Any, report: Any) -> tuple:
        seen.clear()
        out = verified(self, frame, report)
        claim = _stats(self, frame, report.hypotheses[0], rival=False)
        found = seen.get("found", [])
        rivals = [_stats(self, frame, h, rival=True) for h in found[: runner.RIVALS_COMPARED]]
        n_rivals = seen.get("rivals", 0)
        checked = rivals[: runner.RIVALS_CHECKED]
        believed = checked if n_rivals > runner.RIVALS_CHECKED else [r for r in checked if r["passed"]]
        passing = [r for r in rivals if r["passed"]]
        complete = len(found) == n_rivals <= runner.RIVALS_COMPARED
        trailing = [r for r in passing if r["outliers"] >= claim["outliers"] + self.checks.outrank_outliers]
        decisions.append(
            {
                "claimed": bool(out[0]),
                "claim": claim,
                "n_rivals": n_rivals,
                "margin": min((r["outliers"] - claim["outliers"] for r in believed), default=None),
                # the claim's scan fit less the best of its credible rivals', when all of them have
                # outrank_outliers more outliers (None: some has fewer, or they are not all known)
                "fit_gap": claim["fit"] - max(r["fit"] or 1.0 for r in passing)
                if complete and passing and len(trailing) == len(passing) and claim["fit"] is not None
                else None,
            }
        )
        return out

    runner.Session._verified, runner.Session._credible = spy_verified, spy_credible  # type: ignore[method-assign]
    try:
        sim_session(config, site, seed).session.run()
    finally:
        runner.Session._verified, runner.Session._credible = verified, credible  # type: ignore[method-assign]
    return decisions


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--starts", type=int, default=100, help="construction-profile starts per sample")
    ap.add_argument("--sweep-starts", type=int, default=20, help="starts per sample at each doubled key")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        jobs = [(s, "", 0.0, seed, work) for s in SITES for seed in range(1, args.starts + 1)]
        jobs += [
            (s, k, v, seed, work)
            for k, v in SWEEPS
            for s in SITES
            for seed in range(1, args.sweep_starts + 1)
        ]
        with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
            decisions = [d for ds in pool.imap_unordered(_session_decisions, jobs) for d in ds]
    split: collections.Counter[tuple[str, str]] = collections.Counter()
    gaps: dict[str, list[float]] = {"right": [], "wrong": []}
    margins: collections.Counter[tuple[str, str]] = collections.Counter()
    for d in decisions:
        place = "right" if d["claim"]["right"] else "wrong"
        if d["claimed"]:
            split[(place, "claimed")] += 1
        elif d["n_rivals"] and d["margin"] is not None:
            split[(place, "held back by credible rivals")] += 1
            if d["claim"]["passed"]:
                margins[(place, f"{d['margin']:+d}" if d["margin"] < 3 else ">=+3")] += 1
        else:
            split[(place, "failed its own checks")] += 1
        if not d["claimed"] and d["claim"]["passed"] and d["fit_gap"] is not None:
            gaps[place].append(d["fit_gap"])
    print(f"{len(jobs)} sessions, {len(decisions)} claim decisions")
    print("| claim at the | decision | count |\n|---|---|---|")
    for (place, what), n in sorted(split.items()):
        print(f"| {place} place | {what} | {n} |")
    print("\nheld back by credible rivals although the claim passes its own checks, by the closest")
    print("credible rival's outliers minus the claim's:")
    print("| claim at the | margin | count |\n|---|---|---|")
    for (place, margin), n in sorted(margins.items()):
        print(f"| {place} place | {margin} | {n} |")
    print("\nheld back although the claim passes its own checks and every credible rival has at least")
    print("outrank_outliers more outliers: the claim's scan fit less the best such rival's")
    print("| claim at the | decisions | largest | share above 0.05 |\n|---|---|---|---|")
    for place, values in gaps.items():
        top = f"{max(values):+.3f}" if values else "-"
        share = f"{sum(v > 0.05 for v in values) / len(values):.2f}" if values else "-"
        print(f"| {place} place | {len(values)} | {top} | {share} |")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
