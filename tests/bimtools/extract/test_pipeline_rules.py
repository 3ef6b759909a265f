"""Pipeline rules on small inputs: duplicates merged, doors without body placed from placement."""

from __future__ import annotations

import ifcopenshell
import ifcopenshell.guid
import numpy as np
import pytest

from bimtools.extract.candidates import _placement_box
from bimtools.extract.pipeline import MERGE_DISTANCE, merge_duplicates
from bimtools.site.records import Feature


def _feature(guid: str, category: str, x: float, y: float) -> Feature:
    return Feature(guid, category, x, y, 0.0, 1.0, 0.9, 2.1, "L1", 0.0, "IfcDoor", f"door {guid}")


def test_features_at_the_same_place_become_one_with_a_note():
    features = [
        _feature("lift", "Lift", 0.0, 0.0),
        _feature("a", "Door", 5.0, 5.0),
        _feature("a-again", "Door", 5.02, 5.01),  # a storefront door exported again
        _feature("twin-of-lift", "Door", 0.1, 0.0),
        _feature("b", "Door", 5.0 + MERGE_DISTANCE + 0.01, 5.0),
    ]
    kept, notes = merge_duplicates(features)
    assert [f.id for f in kept] == ["lift", "a", "b"]
    assert len(notes) == 2
    assert "a-again" in notes[0] and "merged into" in notes[0] and "(a)" in notes[0]
    assert "twin-of-lift" in notes[1] and "Lift" in notes[1]


def test_distinct_features_are_kept():
    features = [_feature(str(i), "Door", 1.0 * i, 0.0) for i in range(5)]
    kept, notes = merge_duplicates(features)
    assert kept == features and notes == []


def test_placement_box_spans_overall_width_along_local_x():
    model = ifcopenshell.file(schema="IFC4")
    placement = model.createIfcLocalPlacement(
        None,
        model.createIfcAxis2Placement3D(
            model.createIfcCartesianPoint((3.0, 4.0, 0.5)),
            model.createIfcDirection((0.0, 0.0, 1.0)),
            model.createIfcDirection((0.0, 1.0, 0.0)),  # local X along world +Y
        ),
    )
    door = model.createIfcDoor(ifcopenshell.guid.new(), None, "Durchgang", ObjectPlacement=placement)
    box = _placement_box(door, 1.2, 2.1)
    assert box[:, 0] == pytest.approx(np.full(4, 3.0))
    assert (box[:, 1].min(), box[:, 1].max()) == pytest.approx((4.0, 5.2))
    assert (box[:, 2].min(), box[:, 2].max()) == pytest.approx((0.5, 2.6))
