"""The class vocabulary: detector names and BIM categories reduce to one canonical class."""

from __future__ import annotations

from initcli.core.features.classes import BUILTIN_CLASSES, ClassMap


def test_case_blanks_plurals_and_synonyms() -> None:
    classes = ClassMap()
    assert [classes.canonical(n) for n in ("Door", " doors ", "DOOR")] == ["door"] * 3
    assert [classes.canonical(n) for n in ("Lift", "elevator", "Elevators")] == ["lift"] * 3
    assert [classes.canonical(n) for n in ("Stair", "staircase", "stairway")] == ["stairs"] * 3
    assert classes.canonical("Window") == "window"  # unknown names are only normalised


def test_the_site_mapping_comes_before_the_synonyms() -> None:
    classes = ClassMap({"Aufzug": "Lift", "Portal": "Doors", " Exit ": "fire exit"})
    assert classes.canonical("aufzug") == "lift"
    assert classes.canonical("PORTAL") == "door"
    assert classes.canonical("exit") == "fire exit"


def test_known_classes() -> None:
    classes = ClassMap({"Portal": "Doors", "exit": "Fire Exit"})
    assert classes.known(["Doors", "Ramps"]) == {*BUILTIN_CLASSES, "ramps", "fire exit"}
    assert ClassMap().known([]) == set(BUILTIN_CLASSES)
