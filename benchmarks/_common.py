"""What every benchmark shares: its ``--quick`` mode, where its inputs are, and a check that it
measures the installed package.

A benchmark runs as ``python benchmarks/bench_NAME.py``: Python puts this folder (and nothing else
of the repository) first on ``sys.path``, so ``import _common`` finds this file and ``bimtools`` /
``initcli`` come from the installed package. No benchmark adds ``tests/`` or the repository root to
``sys.path``: ``tests/bimtools`` would shadow the package.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import sys
from pathlib import Path
from typing import Any

__all__ = ["ROOT", "SAMPLES", "SHARED_IFC", "parse_args", "package_origin"]

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_models"  # the bundled sample models (every quick mode uses only these)
SHARED_IFC = ROOT.parent / "shared" / "ifc"  # the real IFC models by others, absent in a bare clone


def package_origin() -> str:
    """Where ``bimtools`` and ``initcli`` are imported from; exits 1 if either is not the installed
    package (a namespace folder such as ``tests/bimtools`` shadowing it)."""
    import bimtools
    import initcli

    where = []
    for module in (bimtools, initcli):
        file = getattr(module, "__file__", None)
        folder = Path(file).resolve().parent if file else None
        if folder is None or folder.parent.name == "tests":
            raise SystemExit(
                f"{module.__name__} is imported from {list(module.__path__)}, not the installed package"
            )
        where.append(f"{module.__name__} {folder}")
    return f"bim-init {importlib.metadata.version('bim-init')}: " + ", ".join(where)


def parse_args(parser: argparse.ArgumentParser, quick: dict[str, Any]) -> argparse.Namespace:
    """``parser``'s arguments plus ``--quick``: a smoke run of seconds (what CI's ``make bench-quick``
    calls) whose defaults are ``quick``; options given on the command line still win. Prints where
    the package comes from."""
    unknown = set(quick) - {action.dest for action in parser._actions}
    if unknown:
        raise ValueError(f"--quick sets options the parser lacks: {sorted(unknown)}")
    shown = "".join(f", {k}={v}" for k, v in quick.items())
    parser.add_argument("--quick", action="store_true", help=f"smoke run of a few seconds{shown}")
    known, _ = parser.parse_known_args()
    if known.quick:
        parser.set_defaults(**quick)
    args = parser.parse_args()
    print(f"{Path(sys.argv[0]).name}{' --quick' if args.quick else ''}: {package_origin()}", flush=True)
    return args
