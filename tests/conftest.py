"""Shared fixtures: paths to the bundled samples and to the real IFC models in ../shared/ifc
(the paths themselves are in :mod:`tests.helpers`)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from tests.helpers import SAMPLES, SHARED_IFC


@pytest.fixture
def shared_ifc_dir() -> Path:
    if not SHARED_IFC.is_dir():
        pytest.skip(f"{SHARED_IFC} is absent (real IFC models from other authors)")
    return SHARED_IFC


@pytest.fixture(scope="session")
def site_a(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site folder extracted from the bundled block_a.ifc (no preview), shared by every test."""
    out = tmp_path_factory.mktemp("detector_sites") / "block_a"
    write_site(out, extract_site(SAMPLES / "block_a.ifc"), preview=False)
    return out
