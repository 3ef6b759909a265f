"""bimtools.extract.settings: each default lies inside its documented range."""

from __future__ import annotations

from bimkit.checks import range_problem
from bimtools.extract import settings


def test_defaults_are_inside_their_ranges() -> None:
    assert range_problem(settings.DEFAULT_SECTION_HEIGHT, **settings.SECTION_HEIGHT_RANGE) is None
    assert range_problem(settings.DEFAULT_RESOLUTION, **settings.RESOLUTION_RANGE) is None


def test_ranges_refuse_their_edges_as_documented() -> None:
    assert range_problem(0.0, **settings.SECTION_HEIGHT_RANGE) is not None  # (0, 10]
    assert range_problem(10.0, **settings.SECTION_HEIGHT_RANGE) is None
    assert range_problem(10.01, **settings.SECTION_HEIGHT_RANGE) is not None
    assert range_problem(0.005, **settings.RESOLUTION_RANGE) is None  # [0.005, 1]
    assert range_problem(0.004, **settings.RESOLUTION_RANGE) is not None
    assert range_problem(1.0, **settings.RESOLUTION_RANGE) is None
    assert range_problem(1.5, **settings.RESOLUTION_RANGE) is not None
