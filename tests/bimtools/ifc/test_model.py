"""Length units: a model authored in millimetres or feet extracts to the same metres."""

from __future__ import annotations

import math

import ifcopenshell
import ifcopenshell.ifcopenshell_wrapper as wrapper
import pytest

from bimtools import samples
from bimtools.extract.pipeline import extract_site

LENGTH_TYPES = {"IfcLengthMeasure", "IfcPositiveLengthMeasure", "IfcNonNegativeLengthMeasure"}


def _declared_type(attribute) -> str:
    kind = attribute.type_of_attribute()
    while True:
        if hasattr(kind, "declared_type") and callable(kind.declared_type):
            inner = kind.declared_type()
            if hasattr(inner, "name"):
                return inner.name()
            kind = inner
            continue
        return kind.name() if hasattr(kind, "name") else ""


def rescale_lengths(model: ifcopenshell.file, factor: float, prefix: str | None, imperial: bool) -> None:
    """Rewrite a metre model in another length unit: every length value times ``factor``."""
    schema = wrapper.schema_by_name(model.schema)
    for entity in model:
        declaration = schema.declaration_by_name(entity.is_a())
        for index, attribute in enumerate(declaration.all_attributes()):
            value = entity[index]
            if value is None:
                continue
            name = attribute.name()
            if entity.is_a("IfcCartesianPoint") and name == "Coordinates":
                entity[index] = tuple(c * factor for c in value)
            elif entity.is_a("IfcCartesianPointList") and name == "CoordList":
                entity[index] = tuple(tuple(c * factor for c in row) for row in value)
            elif _declared_type(attribute) in LENGTH_TYPES and isinstance(value, float):
                entity[index] = value * factor
    for unit in model.by_type("IfcSIUnit"):
        if unit.UnitType == "LENGTHUNIT":
            if imperial:
                dims = model.createIfcDimensionalExponents(1, 0, 0, 0, 0, 0, 0)
                metre = model.createIfcSIUnit(None, "LENGTHUNIT", None, "METRE")
                factor_to_m = model.createIfcMeasureWithUnit(model.createIfcLengthMeasure(0.3048), metre)
                foot = model.createIfcConversionBasedUnit(dims, "LENGTHUNIT", "FOOT", factor_to_m)
                for assignment in model.by_type("IfcUnitAssignment"):
                    assignment.Units = tuple(u for u in assignment.Units if u != unit) + (foot,)
            else:
                unit.Prefix = prefix


def _write(path, model):
    model.write(str(path))
    return path


@pytest.mark.parametrize(
    ("factor", "prefix", "imperial", "unit"),
    [(1000.0, "MILLI", False, "MILLIMETRE"), (1 / 0.3048, None, True, "FOOT")],
)
def test_other_length_units_give_the_same_features(tmp_path, factor, prefix, imperial, unit):
    model, _ = samples.build("block_a")
    reference = {f.id: f for f in extract_site(_write(tmp_path / "m.ifc", model)).features}
    scaled, _ = samples.build("block_a")
    rescale_lengths(scaled, factor, prefix, imperial)
    site = extract_site(_write(tmp_path / "scaled.ifc", scaled))
    assert site.info.length_unit == unit
    assert site.info.unit_scale == pytest.approx(1 / factor)
    got = {f.id: f for f in site.features}
    assert sorted(got) == sorted(reference)
    for guid, f in got.items():
        ref = reference[guid]
        assert math.hypot(f.x - ref.x, f.y - ref.y) < 0.01
        assert f.width == pytest.approx(ref.width, abs=0.01) and f.height == pytest.approx(
            ref.height, abs=0.01
        )
