"""bimtools.settings: each default lies inside its documented range."""

from __future__ import annotations

from bimkit.checks import range_problem
from bimtools import settings


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


def test_landmark_defaults_are_inside_their_ranges_and_off() -> None:
    d = settings.LandmarkSettings()
    assert not d.enabled
    for key, bounds in settings.LANDMARK_RANGES.items():
        value = getattr(d, key)
        for v in value if isinstance(value, tuple) else (value,):
            assert range_problem(v, **bounds) is None, key


def test_landmarks_block_parses() -> None:
    assert settings.parse_landmarks(None, "x") == settings.LandmarkSettings()
    assert settings.parse_landmarks({}, "x").enabled  # a block without `enabled` asks for them
    assert not settings.parse_landmarks({"enabled": False}, "x").enabled
    s = settings.parse_landmarks({"corner_angle": [70, 110], "min_leg": 0.5, "opening_width": [0.8, 2]}, "x")
    assert (s.corner_angle, s.min_leg, s.opening_width) == ((70.0, 110.0), 0.5, (0.8, 2.0))
