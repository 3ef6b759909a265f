"""Benchmark bim-extract against the geometry kernel's floor.

For each IFC file: seconds and peak memory of a full ``bim-extract`` run (open, geometry,
sections, features, maps, previews, writing), and of a bare ``ifcopenshell.geom.iterator`` pass
(open + iterate) over the same elements; prints the ratio ours / bare. Goal: ratio <= 1.3.

    python benchmarks/bench_extract.py [--quick] [MODEL.ifc ...] [--repeat 1]

Without models: the real IFC models in ../shared/ifc (skipped with a note where that folder is
absent) and the bundled samples; ``--quick``: the samples only. Each measurement runs in a fresh
process so peak memory (ru_maxrss) is its own.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import SAMPLES, SHARED_IFC, parse_args


def _child(mode: str, path: str) -> None:
    import ifcopenshell
    import ifcopenshell.geom

    from bimtools.extract.candidates import collect_candidates
    from bimtools.extract.output import write_site
    from bimtools.extract.pipeline import extract_site
    from bimtools.ifc.categories import load_categories

    # Imports are paid once per process by both modes and are not what is compared.
    start = time.perf_counter()
    if mode == "bare":
        model = ifcopenshell.open(path)
        elements = collect_candidates(model, load_categories()).all()
        settings = ifcopenshell.geom.settings()
        settings.set("use-world-coords", True)
        iterator = ifcopenshell.geom.iterator(settings, model, multiprocessing.cpu_count(), include=elements)
        count = 0
        if iterator.initialize():
            while True:
                iterator.get()
                count += 1
                if not iterator.next():
                    break
        del iterator
    else:
        site = extract_site(Path(path), storey=None)
        with tempfile.TemporaryDirectory() as out:
            write_site(Path(out) / "site", site)
        count = len(site.features)
    seconds = time.perf_counter() - start
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps({"seconds": seconds, "peak_mb": peak_mb, "count": count}))


def measure(mode: str, path: Path, repeat: int) -> dict:
    best: dict | None = None
    for _ in range(repeat):
        out = subprocess.run(
            [sys.executable, __file__, "--child", mode, str(path)], capture_output=True, text=True
        )
        if out.returncode != 0:
            raise SystemExit(f"{path}: {mode} run failed:\n{out.stderr}")
        result = json.loads(out.stdout.strip().splitlines()[-1])
        if best is None or result["seconds"] < best["seconds"]:
            best = result
    assert best is not None
    return best


def default_models() -> list[Path]:
    """The real IFC models in ../shared/ifc, where that folder is, and the bundled samples."""
    shared = sorted(SHARED_IFC.glob("*.ifc"))
    if not shared:
        print(f"({SHARED_IFC} is absent or empty: the real IFC models are skipped, the samples only)")
    return shared + sorted(SAMPLES.glob("*.ifc"))


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("models", nargs="*", type=Path, help="IFC files (default: see above)")
    parser.add_argument("--repeat", type=int, default=1, help="runs per measurement; the fastest is kept")
    parser.add_argument("--child", nargs=2, metavar=("MODE", "PATH"), help=argparse.SUPPRESS)
    if "--child" in sys.argv:
        args = parser.parse_args()
        _child(*args.child)
        return
    args = parse_args(parser, quick={"models": sorted(SAMPLES.glob("*.ifc"))})
    models = args.models or default_models()
    print(f"{'model':55s} {'bare s':>8s} {'ours s':>8s} {'ratio':>6s} {'peak MB':>8s} {'features':>8s}")
    worst = 0.0
    for path in models:
        bare = measure("bare", path, args.repeat)
        ours = measure("ours", path, args.repeat)
        ratio = ours["seconds"] / bare["seconds"]
        worst = max(worst, ratio)
        print(
            f"{path.name:55s} {bare['seconds']:8.2f} {ours['seconds']:8.2f} {ratio:6.2f} "
            f"{ours['peak_mb']:8.0f} {ours['count']:8d}",
            flush=True,
        )
    print(f"worst ratio {worst:.2f} (goal <= 1.3) on {multiprocessing.cpu_count()} cores")


if __name__ == "__main__":
    main()
