"""bimtools.site.names: the one rule for storey names in file names."""

from __future__ import annotations

import numpy as np

from bimtools.fonts import font_families, put_text
from bimtools.site.names import MAX_SLUG, storey_slug, storey_slugs


def test_letters_of_any_script_are_kept() -> None:
    assert storey_slug("Уровень 1") == "Уровень_1"
    assert storey_slug("Étage 2") == "Étage_2"
    assert storey_slug("E\u0301tage 2") == "Étage_2"  # decomposed (macOS) and composed: one slug
    assert storey_slug("階 3") == "階_3"
    assert storey_slug("1") == "1"
    assert storey_slug("  B1 / Car park ") == "B1_Car_park"
    assert storey_slug("Level -1") == "Level_-1"  # apart from "Level 1"


def test_an_empty_name_gets_a_stable_hash_name() -> None:
    assert storey_slug("").startswith("storey_")
    assert storey_slug("///") == storey_slug("///") != storey_slug("")
    assert len(storey_slug("x" * 500)) == MAX_SLUG


def test_names_that_collide_get_a_numeric_suffix() -> None:
    assert storey_slugs(["Уровень 1", "Уровень/1", "уровень 1", "", "Étage 2", "階 3", "1"]) == [
        "Уровень_1",
        "Уровень_1_2",
        "уровень_1_3",  # a case-insensitive file system would merge it with the first
        storey_slug(""),
        "Étage_2",
        "階_3",
        "1",
    ]


def test_preview_text_draws_cyrillic_glyphs_not_question_marks() -> None:
    assert font_families()[0] == "DejaVu Sans"
    cyrillic = np.full((40, 200, 3), 255, np.uint8)
    marks = np.full((40, 200, 3), 255, np.uint8)
    put_text(cyrillic, "Уровень 1", (5, 30), 18, (0, 0, 0))
    put_text(marks, "??????? 1", (5, 30), 18, (0, 0, 0))
    assert (cyrillic < 128).any()
    assert not np.array_equal(cyrillic, marks)
    put_text(cyrillic, "bad \udcff name", (5, 30), 18, (0, 0, 0))  # a lone surrogate does not raise
