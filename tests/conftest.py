"""Shared fixtures: paths to the bundled samples and to the real IFC models in ../shared/ifc."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_models"
SHARED_IFC = ROOT.parent / "shared" / "ifc"


def shared_ifc_files() -> list[Path]:
    return sorted(SHARED_IFC.glob("*.ifc")) if SHARED_IFC.is_dir() else []


@pytest.fixture
def shared_ifc_dir() -> Path:
    if not SHARED_IFC.is_dir():
        pytest.skip(f"{SHARED_IFC} is absent (real IFC models from other authors)")
    return SHARED_IFC
