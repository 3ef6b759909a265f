"""Lift evidence: a lift space is a shaft only when shaft-sized; exterior doors enter nothing."""

from __future__ import annotations

from bimtools.extract.circulation import SideProbe
from bimtools.extract.features import is_shaft_space
from bimtools.ifc.categories import load_categories


def _category(name: str):
    return next(c for c in load_categories().categories if c.name == name)


def test_a_big_space_named_elevator_is_no_shaft():
    lift = _category("Lift")
    assert lift.is_space("Elevator (N.I.C.)")
    assert is_shaft_space(lift, 5.0)
    assert not is_shaft_space(lift, 40.0)  # a lobby-sized "Elevator (N.I.C.)" placeholder
    assert is_shaft_space(_category("Stairs"), 40.0)  # staircases are not bounded by this rule


def test_outside_is_not_reachable():
    assert not SideProbe(label=0, space="", point=(0.0, 0.0)).reachable
    assert SideProbe(label=0, space="Lift", point=(0.0, 0.0), space_index=2, space_area=4.0).reachable
    assert SideProbe(label=5, space="", point=(0.0, 0.0)).reachable
