"""What bim-extract drops is said and counted; stairs whose geometry is on parts of other classes
(landings, stringers: IfcMember, IfcSlab, proxies) are read from those parts."""

from __future__ import annotations

from pathlib import Path

import ifcopenshell
import ifcopenshell.api.root
import ifcopenshell.util.element

from bimtools.extract.pipeline import extract_site
from tests.helpers import SAMPLES


def _stairs(site) -> int:  # type: ignore[no-untyped-def]
    return sum(1 for f in site.features if f.category == "Stairs")


def _rewrite(tmp_path: Path, change) -> Path:  # type: ignore[no-untyped-def]
    model = ifcopenshell.open(SAMPLES / "block_a.ifc")
    change(model)
    path = tmp_path / "changed.ifc"
    model.write(str(path))
    return path


def test_a_stair_whose_flights_are_other_classes_is_still_extracted(tmp_path: Path) -> None:
    before = _stairs(extract_site(SAMPLES / "block_a.ifc"))

    def flights_as_members(model: ifcopenshell.file) -> None:
        for flight in list(model.by_type("IfcStairFlight")):
            ifcopenshell.api.root.reassign_class(model, product=flight, ifc_class="IfcMember")

    site = extract_site(_rewrite(tmp_path, flights_as_members))
    assert before > 0
    assert _stairs(site) == before
    assert not site.skipped


def test_a_stair_without_any_geometry_is_counted_as_skipped(tmp_path: Path) -> None:
    def no_geometry(model: ifcopenshell.file) -> None:
        for stair in model.by_type("IfcStair"):
            for part in ifcopenshell.util.element.get_decomposition(stair):
                part.Representation = None
            stair.Representation = None

    site = extract_site(_rewrite(tmp_path, no_geometry))
    # (its enclosure doors may still be Stairs features: those need no stair geometry)
    n = len(ifcopenshell.open(SAMPLES / "block_a.ifc").by_type("IfcStair"))
    assert f"{n} IfcStair (no geometry)" in site.skipped_summary()
    assert any("no body, nor parts with one" in w for w in site.warnings)
