"""Paths the tests share: the repository root, the bundled samples, the real IFC models in ../shared/ifc.

Test modules import these as ``from tests.helpers import SAMPLES`` (pytest's ``pythonpath`` puts the
repository root on ``sys.path``); the fixtures built on them live in ``tests/conftest.py``.
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_models"
SCHEMAS = ROOT / "schemas"
SHARED_IFC = ROOT.parent / "shared" / "ifc"


def shared_ifc_files() -> list[Path]:
    """The real IFC models in ../shared/ifc, sorted (none when the folder is absent)."""
    return sorted(SHARED_IFC.glob("*.ifc")) if SHARED_IFC.is_dir() else []
