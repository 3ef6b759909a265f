"""Benchmark ``bim-init survey`` on the three samples: speed, and agreement with the simulated sessions.

- speed: a storey's samples (``--spacing`` 1 m x ``--headings`` 4) surveyed on ``--workers`` processes (goal:
  under a minute on 2 cores), and the greedy landmark suggestion;
- agreement: the survey's distance to a unique match at the eval's own random starts (seed 1 + k,
  the starts ``bim-init eval`` draws) against the eval's measured coarse distance of the ``bim``
  method (100 starts; by default the README's numbers below, with ``--results DIR/results.jsonl``
  of an ideal-world eval run its own: the mean and median over its localised ``bim`` starts, and
  per start as well, the share within 25 %);
- initialised: the share of those starts the survey places within ``limits.max_distance`` (the
  camera's Algorithm 1 or the session's lidar registration along the loop, whichever first) beside
  the eval's share localised, per storey, and the mean distance of those placed. ``--camera off``
  surveys a robot whose camera sees nothing, for an eval with ``sim.miss_rate: 1``; ``--reality
  construction`` surveys the site as built, for an eval run with ``--reality construction``;
  ``--method`` and ``--sweep-value`` pick the eval's rows (``--sweep registration.min_fit=0.7,0.8``:
  ``0.7``).

    python benchmarks/bench_survey.py [--quick] [--workers 2] [--starts 100] [--models ...] [--results FILE]
                                      [--method bim+pf] [--sweep-value V] [--camera on|off]
                                      [--reality ideal|construction]
                                      [--eval-config sample_models/eval_real.yaml]
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from _common import SAMPLES, parse_args

EVAL_MEAN = {"ntu_hallway": 30.4, "block_a": 14.3, "block_b": 20.8}  # m, README Results, bim, 100 starts
EVAL_MEDIAN = {"ntu_hallway": 28.0, "block_a": 3.2, "block_b": 4.3}


def main() -> None:
    from initcli.cli.survey import survey_params
    from initcli.config import REALITY_PROFILES, load_config
    from initcli.config.building import choose_storey, prepare_site
    from initcli.eval.trial import trial_seed
    from initcli.executor import LocalExecutor
    from initcli.sim.build import build_sim
    from initcli.survey.landmarks import suggest_landmarks
    from initcli.survey.plan import plan_storey
    from initcli.survey.run import survey_storey
    from initcli.survey.summary import summarise

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--starts", type=int, default=100, help="eval starts compared per sample")
    ap.add_argument("--models", default="ntu_hallway,block_a,block_b")
    ap.add_argument(
        "--eval-config",
        type=Path,
        default=None,
        help="survey the sites of this eval config instead of --models (sample_models/eval_real.yaml)",
    )
    ap.add_argument(
        "--results", type=Path, default=None, help="an eval results.jsonl for per-start agreement"
    )
    ap.add_argument("--method", default="bim", help="the eval method of --results compared")
    ap.add_argument(
        "--sweep-value", default=None, help="with a swept --results: the rows of this sweep value only"
    )
    ap.add_argument(
        "--camera",
        choices=("on", "off"),
        default="on",
        help="off: the survey of a robot whose camera sees nothing (an eval with sim.miss_rate 1)",
    )
    ap.add_argument(
        "--reality",
        choices=tuple(REALITY_PROFILES),
        default=None,
        help="survey (and draw the starts) in this reality, for an eval run with the same --reality",
    )
    ap.add_argument("--no-landmarks", action="store_true")
    ap.add_argument("--spacing", type=float, default=1.0, help="m between surveyed positions")
    ap.add_argument("--headings", type=int, default=4, help="headings surveyed at each position")
    args = parse_args(ap, quick={"starts": 5, "spacing": 4.0, "headings": 2})
    measured: dict[tuple[str, int], float] = {}
    if args.results is not None:
        for line in args.results.read_text().splitlines():
            r = json.loads(line)
            swept = (
                str(r.get("sweep_value")) == args.sweep_value if args.sweep_value else not r.get("sweep_key")
            )
            if r["method"] == args.method and swept:
                # by the trial's seed (an eval resumed with another seed numbers its starts anew)
                measured[(r["site"], int(r.get("seed", 1 + int(r["start"]))))] = (
                    float(r["distance_m"]) if r["localised"] else math.inf
                )
    executor = LocalExecutor(args.workers)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, config_path in _sites(args):
            config = load_config(config_path, args.reality)
            site = prepare_site(config, Path(tmp) / name)
            simulated, _ = choose_storey(config, site)
            params = replace(
                survey_params(config, args.spacing, args.headings), camera_on=args.camera == "on"
            )
            t0 = time.perf_counter()
            plan = plan_storey(site.storeys[simulated], params)
            result, views = survey_storey(plan, params, executor)
            t_survey = time.perf_counter() - t0
            t_land = math.nan
            if not args.no_landmarks:
                t1 = time.perf_counter()
                suggest_landmarks(result, views, 2, executor)
                t_land = time.perf_counter() - t1
            summary = summarise(result)
            # the eval's starts: the same random corridor starts bim-init eval draws (seed 1 + k)
            starts = [build_sim(config, site, simulated, trial_seed(1, k)).start for k in range(args.starts)]
            plan.starts = np.array([[s.x, s.y, s.yaw] for s in starts])
            plan.position = np.arange(len(starts))
            at = survey_storey(plan, params, executor)[0].distance  # the camera or the lidar, first
            placed = np.isfinite(at) & (at <= params.limit_m)
            at = np.minimum(at, params.limit_m)
            eval_mean, eval_median = EVAL_MEAN.get(name), EVAL_MEDIAN.get(name)
            localised = [m for (where, _), m in measured.items() if where == name and math.isfinite(m)]
            if any(where == name for where, _ in measured):  # the given eval's own numbers, not the README's
                eval_mean = round(float(np.mean(localised)), 1) if localised else None
                eval_median = round(float(np.median(localised)), 1) if localised else None
            line = {
                "model": name,
                "storey": simulated,
                "samples": summary["samples"],
                "survey_s": round(t_survey, 1),
                "landmarks_s": round(t_land, 1),
                "survey_median_m": summary["median_distance_m"],
                "unique_within": summary["unique_within"],
                "at_eval_starts_mean_m": round(float(at.mean()), 1),
                "at_eval_starts_median_m": round(float(np.median(at)), 1),
                "eval_mean_m": eval_mean,
                "eval_median_m": eval_median,
                "mean_ratio": round(float(at.mean()) / eval_mean, 2) if eval_mean else None,
                "survey_initialised": round(float(placed.mean()), 2),
                "survey_initialised_mean_m": round(float(at[placed].mean()), 1) if placed.any() else None,
            }
            mine = [m for (where, _), m in measured.items() if where == name]
            if mine:  # the eval's share of its starts initialised, beside the survey's
                line["eval_initialised"] = round(len(localised) / len(mine), 2)
            seeds = [trial_seed(1, k) for k in range(len(at))]
            pairs = [(at[k], measured[(name, q)]) for k, q in enumerate(seeds) if (name, q) in measured]
            if pairs:
                within = [
                    abs(a - min(m, params.limit_m)) <= 0.25 * max(min(m, params.limit_m), 1.0)
                    for a, m in pairs
                ]
                line["per_start_within_25pct"] = f"{sum(within)}/{len(within)}"
            rows.append(line)
            print(json.dumps(line), flush=True)
    executor.close()
    print(
        "\n| model | starts surveyed | survey s | landmarks s | survey at eval starts mean / median"
        " | eval mean / median | ratio | initialised: survey / eval | mean m of those: survey / eval |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['model']} | {r['samples']} | {r['survey_s']} | {r['landmarks_s']} | "
            f"{r['at_eval_starts_mean_m']} / {r['at_eval_starts_median_m']} m | "
            f"{r['eval_mean_m']} / {r['eval_median_m']} m | {r['mean_ratio']} | "
            f"{r['survey_initialised']} / {r.get('eval_initialised', '-')} | "
            f"{r['survey_initialised_mean_m']} / {r['eval_mean_m']} |"
        )


def _sites(args: argparse.Namespace) -> list[tuple[str, Path]]:
    """(name, site config) of every site surveyed: an eval config's sites (named as the eval names
    them, the config's stem), or the bundled samples of ``--models``."""
    if args.eval_config is None:
        return [(name, SAMPLES / f"{name}.site.yaml") for name in args.models.split(",")]
    import yaml

    doc = yaml.safe_load(args.eval_config.read_text())
    found = []
    for entry in doc["sites"]:
        path = (args.eval_config.parent / entry["config"]).resolve()
        found.append((path.name.removesuffix(".site.yaml"), path))
    return found


if __name__ == "__main__":
    main()
