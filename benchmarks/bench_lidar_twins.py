"""The camera off, split by what a lidar can know: an eval's starts in spaces with a lidar twin
(``bim-init survey``'s ``lidar_twins``: doors shut, a turn or shift lays the space's walls on walls
and floor on floor) against the starts elsewhere.

A start in a twin space fits its twin pose as well as its own for every scan (to within the
session's ``verification.scan_tolerance``, by which every lidar check judges a fit), so with the
camera off and the BIM's doors shut (the ideal world) a session initialises there only where a
difference within that tolerance happens to show (beams of the twin pose through a thin wall). The
records' camera-off starts are split by the survey's mask of twin spaces: the successes among
starts elsewhere are what a lidar-only initialisation can be judged on, and the successes inside
twin spaces (printed, expected 0 in the ideal world) are such chance differences. The sessions
are not run again: the starts and outcomes come from eval records (``results.jsonl``), the sites
from the eval configs.

    python benchmarks/bench_lidar_twins.py [--quick] [--run CONFIG RESULTS] ...

Default: the samples (``sample_models/eval.yaml``, record ``start0_camera_off_ideal``) and, where
``../shared/ifc`` is, the real models (``eval_real.yaml``, record ``start0_real_camera_off_ideal``);
``--quick``: the samples only. About 10 s per storey (extraction and the survey's plan).
"""

from __future__ import annotations

import argparse
import collections
import json
import tempfile
from pathlib import Path
from typing import Any

from _common import ROOT, SAMPLES, SHARED_IFC, parse_args

RECORDS = ROOT / "benchmarks" / "results"
SAMPLE_RUN = (SAMPLES / "eval.yaml", RECORDS / "start0_camera_off_ideal" / "results.jsonl")
REAL_RUN = (SAMPLES / "eval_real.yaml", RECORDS / "start0_real_camera_off_ideal" / "results.jsonl")


def twin_masks(eval_config: Path, names: set[str], workdir: Path) -> dict[str, Any]:
    """Per eval site name: (the storey's survey plan) for the sites ``names`` of ``eval_config``."""
    from initcli.config import load_config
    from initcli.config.building import choose_storey, prepare_site
    from initcli.eval.config import load_eval_config
    from initcli.match.pipeline import site_class_map
    from initcli.survey.plan import SurveyParams, plan_storey

    plans: dict[str, Any] = {}
    models: dict[Path, Any] = {}  # by IFC model: one extraction for all its storeys
    for site in load_eval_config(eval_config).sites:
        if site.name not in names:
            continue
        config = load_config(site.config)
        if config.site_path() not in models:
            models[config.site_path()] = prepare_site(config, workdir / site.name)
        model = models[config.site_path()]
        simulated, _ = choose_storey(config, model)
        params = SurveyParams(spacing=1.0, headings=1, scan_tolerance=config.verification.scan_tolerance)
        plans[site.name] = plan_storey(model.storeys[simulated], params, site_class_map(model))
        print(
            f"  {site.name}: storey {simulated}, {len(plans[site.name].lidar_twins)} twin space(s)",
            flush=True,
        )
    return plans


def split(eval_config: Path, results: Path, workdir: Path) -> dict[str, collections.Counter[str]]:
    """Per site: the record's starts counted by (in a twin space or not) x (initialised or not)."""
    rows = [json.loads(line) for line in results.read_text().splitlines() if line.strip()]
    rows = [r for r in rows if r["method"] == "bim+pf" and not r.get("sweep_key") and not r.get("refused")]
    plans = twin_masks(eval_config, {r["site"] for r in rows}, workdir)
    out: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    for r in rows:
        plan = plans[r["site"]]
        grid = plan.circulation.grid
        row, col = grid.world_to_cell(r["start_pose"][0], r["start_pose"][1])
        cells = plan.lidar_twin_cells
        inside = cells is not None and 0 <= row < cells.shape[0] and 0 <= col < cells.shape[1]
        twin = bool(inside and cells[row, col])
        out[r["site"]][f"{'twin' if twin else 'elsewhere'} {'ok' if r['success'] else 'failed'}"] += 1
        out[r["site"]]["confident_wrong"] += bool(r["confident_wrong"])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--run",
        nargs=2,
        action="append",
        type=Path,
        metavar=("CONFIG", "RESULTS"),
        help="an eval config and the results.jsonl of a camera-off run of it (repeatable)",
    )
    ap.add_argument("--real", action=argparse.BooleanOptionalAction, default=True, help="the real models too")
    args = parse_args(ap, quick={"real": False})
    runs = [tuple(r) for r in args.run] if args.run else [SAMPLE_RUN]
    if not args.run and args.real and SHARED_IFC.is_dir():
        runs.append(REAL_RUN)
    total: collections.Counter[str] = collections.Counter()
    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (config, results) in enumerate(runs):
            print(f"{results} ({config}):", flush=True)
            for site, c in sorted(split(config, results, Path(tmp) / str(k)).items()):
                twin, elsewhere = _starts(c)
                ok = f"{c['twin ok']} / {twin} | {c['elsewhere ok']} / {elsewhere}"
                lines.append(f"| {site} | {twin + elsewhere} | {ok} |")
                total.update(c)
    print("\n| site | starts | in twin spaces: initialised / all | elsewhere: initialised / all |")
    print("|---|---|---|---|")
    print("\n".join(lines))
    twin, elsewhere = _starts(total)
    share = total["elsewhere ok"] / elsewhere if elsewhere else float("nan")
    print(
        f"\nstarts where a lidar can tell the places apart: {total['elsewhere ok']} / {elsewhere} "
        f"initialised ({100 * share:.1f} %); in lidar-twin spaces: {twin} starts, {total['twin ok']} "
        f"initialised (expected 0 with the doors shut); confident-wrong: {total['confident_wrong']}"
    )


def _starts(c: collections.Counter[str]) -> tuple[int, int]:
    """Starts in twin spaces, starts elsewhere."""
    return c["twin ok"] + c["twin failed"], c["elsewhere ok"] + c["elsewhere failed"]


if __name__ == "__main__":
    main()
