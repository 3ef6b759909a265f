"""``python -m bimtools.samples --out sample_models [--name NAME ...]``: write the sample models."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from bimtools.samples import MODELS, write

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bimtools.samples",
        description="Write the deterministic sample IFC models and their ground truth (<name>.truth.json).",
    )
    parser.add_argument(
        "--out", type=Path, default=Path("sample_models"), help="output folder (default: %(default)s)"
    )
    parser.add_argument(
        "--name", action="append", choices=MODELS, help="model to write (repeatable; default: all of them)"
    )
    args = parser.parse_args(argv)
    for name in args.name or MODELS:
        start = time.perf_counter()
        ifc_path, truth_path = write(name, args.out)
        print(f"{ifc_path} + {truth_path.name}  ({time.perf_counter() - start:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
