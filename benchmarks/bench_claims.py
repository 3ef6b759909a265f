"""Which claim checks matter: every unique match a session considers claiming, right or wrong, and
every set of several hypotheses the lidar along the path is asked to tell apart.

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

The lidar along the path (``track_outranks``): for every pair of hypotheses that pass the recent
checks in one decision (a claim and a rival, or two of several hypotheses), the scans of the path
fitted window by window for each (``tracked_scan_fit``, from where its recent scans fit best).
Prints, by whether each is at the right place, how much the one fits its best window better than
the other, and how often ``track_outranks`` would let a wrong place outrank the right one (the
count that must stay 0) against how often it lets the right place outrank a wrong one; and, for
the pairs where B needs more outliers than A, how that count grows as the lead asked for over such
a B shrinks (what ``track_lead_trailing`` rests on). ``--dump`` keeps every decision (pickled) for
studying other rules offline.

    python benchmarks/bench_claims.py [--quick] [--starts 100] [--sweep-starts 20] [--first-seed 1]
                                      [--workers 2] [--dump decisions.pkl]

It instruments ``Session._verified``, ``Session._credible`` and ``Session._match`` (private: this
script is a measurement of the runner, not an API), and computes the path's fit of every rival:
about 40 minutes on 2 cores with the defaults.
"""

from __future__ import annotations

import argparse
import collections
import math
import multiprocessing
import pickle
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from _common import SAMPLES, parse_args

SITES = ("block_a", "block_b", "ntu_hallway")
SWEEPS = (("sim.as_built.door_shift", 0.6), ("sim.as_built.missing_doors", 0.4))
WRONG_M, WRONG_DEG = 2.0, 30.0
TRACKED_RIVALS = 24  # rivals of a claim whose path fit is recorded
_SITES: dict[tuple[str, str, float], Any] = {}


def _stats(claims: Any, frame: Any, hypothesis: Any, rival: bool) -> dict[str, Any]:
    """Outliers, rightness, checks, scan fit and the path's fit of one hypothesis at ``frame``
    (``claims``: the session's :class:`initcli.session.claims.ClaimChecks`)."""
    truth = frame.truth
    pose = hypothesis.reported_pose
    check = claims.verify(hypothesis.storey, pose * frame.odom.inverse(), rival=rival)
    yaw = abs(math.degrees(math.atan2(math.sin(pose.yaw - truth.yaw), math.cos(pose.yaw - truth.yaw))))
    return {
        "outliers": hypothesis.n_outliers,
        "inliers": hypothesis.n_inliers,
        "right": math.hypot(pose.x - truth.x, pose.y - truth.y) < WRONG_M and yaw < WRONG_DEG,
        "error": (round(math.hypot(pose.x - truth.x, pose.y - truth.y), 2), round(yaw, 1)),
        "passed": check.passed,
        "fit": check.scan_fit,
        "track": claims.track(frame, hypothesis, check),
        "wide": claims.track(frame, hypothesis, check, wide=True),
    }


def _session_decisions(job: tuple[str, str, float, int, str]) -> list[dict[str, Any]]:
    from initcli.config import load_config
    from initcli.config.building import prepare_site
    from initcli.core.verify.checks import TRACK_HYPOTHESES, trails
    from initcli.eval.sweep import apply_sweep, parse_sweep
    from initcli.session import runner
    from initcli.session.claims import ClaimChecks
    from initcli.session.simulated import sim_session

    name, key, value, seed, work = job
    config = load_config(SAMPLES / f"{name}.site.yaml", "construction")
    if key:
        config = apply_sweep(config, parse_sweep(f"{key}={value}"), value)
    if (name, key, value) not in _SITES:  # one extraction per sample and sweep value in each worker
        _SITES[(name, key, value)] = prepare_site(config, Path(work) / f"{name}_{key}_{value}_{seed}")
    site = _SITES[(name, key, value)]
    decisions: list[dict[str, Any]] = []
    seen: dict[str, Any] = {}
    where = f"{name} seed {seed}" + (f" {key}={value}" if key else "")
    verified, credible, match = ClaimChecks.verified, ClaimChecks.credible, runner.Session._match

    def spy_credible(
        self: Any, frame: Any, check: Any, track: Any, claim: Any, rivals: int, found: list
    ) -> tuple:
        seen["rivals"], seen["found"] = rivals, list(found)
        return credible(self, frame, check, track, claim, rivals, found)

    def spy_verified(self: Any, frame: Any, report: Any, picked: bool = False) -> tuple:
        seen.clear()
        out = verified(self, frame, report, picked)
        claim = _stats(self, frame, report.hypotheses[0], rival=False)
        found = seen.get("found", [])
        limits = self.checks.rivals  # verification.rivals
        rivals = [_stats(self, frame, h, rival=True) for h in found[: limits.compared]]
        n_rivals = seen.get("rivals", 0)
        checked = rivals[: limits.checked]
        believed = checked if n_rivals > limits.checked else [r for r in checked if r["passed"]]
        passing = [r for r in rivals if r["passed"]]
        complete = len(found) == n_rivals <= limits.compared
        trailing = [r for r in passing if trails(claim["outliers"], r["outliers"], self.checks)]
        decisions.append(
            {
                "kind": "claim",
                "where": where,
                "t": frame.t,
                "claimed": bool(out[0]),
                "claim": claim,
                "n_rivals": n_rivals,
                "rivals": rivals[:TRACKED_RIVALS],
                "margin": min((r["outliers"] - claim["outliers"] for r in believed), default=None),
                # the claim's scan fit less the best of its credible rivals', when all of them have
                # outrank_outliers more outliers (None: some has fewer, or they are not all known)
                "fit_gap": claim["fit"] - max(r["fit"] or 1.0 for r in passing)
                if complete and passing and len(trailing) == len(passing) and claim["fit"] is not None
                else None,
            }
        )
        return out

    def spy_match(self: Any, t: float) -> Any:
        report = match(self, t)
        frame = seen.get("frame")
        several = 1 < report.n_hypotheses <= min(len(report.hypotheses), TRACK_HYPOTHESES)
        if frame is not None and several:
            hs = [_stats(self.claims, frame, h, rival=True) for h in report.hypotheses]
            decisions.append({"kind": "several", "hypotheses": hs, "where": where, "t": t})
        return report

    perceive = runner.Session._perceive

    def spy_perceive(self: Any, frame: Any) -> bool:
        seen["frame"] = frame
        return perceive(self, frame)

    ClaimChecks.verified, ClaimChecks.credible = spy_verified, spy_credible  # type: ignore[method-assign]
    runner.Session._match, runner.Session._perceive = spy_match, spy_perceive  # type: ignore[method-assign]
    try:
        sim_session(config, site, seed).session.run()
    finally:
        ClaimChecks.verified, ClaimChecks.credible = verified, credible  # type: ignore[method-assign]
        runner.Session._match, runner.Session._perceive = match, perceive  # type: ignore[method-assign]
    return decisions


@dataclass(frozen=True)
class TrackPair:
    """Hypothesis A against hypothesis B of one decision, by the lidar along the path."""

    wins: bool  # track_outranks(A, B) as the session asks it: B's path as found and searched wide
    trailing: bool  # B needs outrank_outliers more outliers than A (``trails``)
    leads: tuple[float, float]  # A's best lead over B's path as found and searched wide ...
    backs: tuple[float, float]  # ... and B's over A's
    windows: int  # windows both paths have
    a_fits: bool  # A's worst window is at least min_track_fit

    @property
    def lead(self) -> float:
        """A's best lead over B (B's path as found) in a window."""
        return self.leads[0]

    @property
    def back(self) -> float:
        """B's best lead over A."""
        return self.backs[0]


def _track_pairs(decisions: list[dict[str, Any]]) -> dict[tuple[bool, bool], list[TrackPair]]:
    """(A right, B right) -> every ordered pair of hypotheses in one decision that the session
    compares by the lidar along the path (a claim that passes the recent checks and each rival that
    does too, either way round; of several hypotheses one that passes them and any other, passing
    or not), with B's path fitted both from where its recent scans fit best and searched wide (as
    the session compares them; a B with outrank_outliers more outliers than A needs only the
    trailing lead)."""
    from initcli.core.verify.checks import VerificationParams, track_outranks, trails

    params = VerificationParams()
    pairs: dict[tuple[bool, bool], list[TrackPair]] = collections.defaultdict(list)
    for d in decisions:
        several = d["kind"] != "claim"
        hs = d["hypotheses"] if several else [d["claim"], *d["rivals"]]
        hs = [h for h in hs if len(h["track"]) and (several or h["passed"])]
        for a in hs:
            for b in hs:
                if a is b or not a["passed"]:
                    continue
                if not several and a is not d["claim"] and b is not d["claim"]:
                    continue
                mine = np.asarray(a["track"])
                both = [np.asarray(b["track"]), np.asarray(b["wide"])]
                n = min(len(mine), *(len(t) for t in both))
                if n == 0:
                    continue
                diff = [mine[:n] - t[:n] for t in both]
                trailing = trails(a["outliers"], b["outliers"], params)
                pair = TrackPair(
                    all(track_outranks(mine, t, params, trailing) for t in both),
                    trailing,
                    (float(diff[0].max()), float(diff[1].max())),
                    (float(-diff[0].min()), float(-diff[1].min())),
                    n,
                    float(mine.min()) >= params.min_track_fit,
                )
                pairs[(a["right"], b["right"])].append(pair)
                if pair.wins and not a["right"] and b["right"]:
                    print(
                        f"  unsafe: {d['where']} t={d['t']:.1f} ({d['kind']}): A {a['error']} "
                        f"{np.round(a['track'], 2)}, B {b['error']} {np.round(b['track'], 2)}"
                    )
    return pairs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--starts", type=int, default=100, help="construction-profile starts per sample")
    ap.add_argument("--sweep-starts", type=int, default=20, help="starts per sample at each doubled key")
    ap.add_argument("--first-seed", type=int, default=1, help="seed of the first start")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--dump", type=Path, help="also pickle every decision here (for offline study of rules)")
    args = parse_args(ap, quick={"starts": 1, "sweep_starts": 1})
    seeds = range(args.first_seed, args.first_seed + args.starts)
    sweep_seeds = range(args.first_seed, args.first_seed + args.sweep_starts)
    with tempfile.TemporaryDirectory() as work:
        jobs = [(s, "", 0.0, seed, work) for s in SITES for seed in seeds]
        jobs += [(s, k, v, seed, work) for k, v in SWEEPS for s in SITES for seed in sweep_seeds]
        with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
            decisions = [d for ds in pool.imap_unordered(_session_decisions, jobs) for d in ds]
    if args.dump:
        with args.dump.open("wb") as f:
            pickle.dump(decisions, f)
    _print_claims(decisions, len(jobs))
    _print_tracks(decisions)
    _print_pairs(decisions)
    sys.stdout.flush()


def _print_claims(decisions: list[dict], n_jobs: int) -> None:
    """How the claim decisions split (claimed, held back by rivals, failed), the rivals' margins and
    the scan-fit gaps of claims held back."""
    claims = [d for d in decisions if d["kind"] == "claim"]
    split: collections.Counter[tuple[str, str]] = collections.Counter()
    gaps: dict[str, list[float]] = {"right": [], "wrong": []}
    margins: collections.Counter[tuple[str, str]] = collections.Counter()
    for d in claims:
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
    several = len(decisions) - len(claims)
    print(f"{n_jobs} sessions, {len(claims)} claim decisions, {several} sets of several hypotheses")
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


def _print_tracks(decisions: list[dict]) -> None:
    """The worst lidar window along the path of every hypothesis passing the recent checks."""
    tracks: list[tuple[bool, np.ndarray]] = []
    for d in decisions:
        for h in [d["claim"], *d["rivals"]] if d["kind"] == "claim" else d["hypotheses"]:
            if h["passed"] and len(h["track"]):
                tracks.append((h["right"], h["track"]))
    print("\nthe lidar along the path: each hypothesis that passes the recent checks, its worst window")
    print("| place | hypotheses | 1st percentile | 5th percentile | median |\n|---|---|---|---|---|")
    for right in (True, False):
        worst = [float(np.min(t)) for r, t in tracks if r is right]
        if worst:
            p1, p5, p50 = np.percentile(worst, [1, 5, 50])
            print(f"| {'right' if right else 'wrong'} | {len(worst)} | {p1:.3f} | {p5:.3f} | {p50:.3f} |")


def _print_pairs(decisions: list[dict]) -> None:
    """Pairs of hypotheses compared by the lidar along the path, and how often A outranks B."""
    from initcli.core.verify.checks import VerificationParams

    params = VerificationParams()
    print("\npairs of hypotheses compared by the lidar along the path (A passing the recent checks, B a")
    print("claim's rival passing them too, or any other of several hypotheses): A's best lead over B in a")
    print("window, B's best lead over A; and how often track_outranks(A, B) holds as the session asks it")
    print(
        f"(lead {params.track_lead}, or {params.track_lead_trailing} over a B with"
        f" {params.outrank_outliers}+ more outliers; slack {params.track_slack}; A's worst window at"
        f" least {params.min_track_fit}; {params.min_track_windows}+ windows)"
    )
    print("| A | B | pairs | A's lead: median / largest | B's lead: median / largest | A outranks B |")
    print("|---|---|---|---|---|---|")
    pairs = _track_pairs(decisions)
    for (a, b), values in sorted(pairs.items(), reverse=True):
        lead = np.array([v.lead for v in values])
        back = np.array([v.back for v in values])
        print(
            f"| {'right' if a else 'wrong'} | {'right' if b else 'wrong'} | {len(values)} | "
            f"{np.median(lead):+.3f} / {lead.max():+.3f} | {np.median(back):+.3f} / {back.max():+.3f} | "
            f"{sum(v.wins for v in values)} |"
        )
    print(
        f"\nthe pairs where B has {params.outrank_outliers}+ more outliers than A (over"
        f" {params.min_track_windows}+"
    )
    print("windows): how often A would outrank B at each lead over both of B's paths (the trailing lead")
    print(
        f"of the session is {params.track_lead_trailing}; slack {params.track_slack},"
        " A's worst window at least"
    )
    print(f"{params.min_track_fit})")
    leads = (0.05, 0.1, 0.15, 0.2)
    print("| A | B | pairs | " + " | ".join(f"lead {x}" for x in leads) + " |")
    print("|---|---|---|" + "---|" * len(leads))
    for (a, b), values in sorted(pairs.items(), reverse=True):
        trailing = [v for v in values if v.trailing and v.windows >= params.min_track_windows]
        counts = [
            sum(v.a_fits and min(v.leads) >= x and max(v.backs) <= params.track_slack for v in trailing)
            for x in leads
        ]
        print(
            f"| {'right' if a else 'wrong'} | {'right' if b else 'wrong'} | {len(trailing)} | "
            + " | ".join(map(str, counts))
            + " |"
        )
    unsafe = sum(v.wins for v in pairs.get((False, True), []))
    print(f"\na wrong place outranking the right one by the lidar along the path: {unsafe} (must be 0)")


if __name__ == "__main__":
    main()
