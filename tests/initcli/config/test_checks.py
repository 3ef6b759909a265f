"""initcli.config.checks: settings within their own ranges that contradict each other, or make no
physical sense for a robot, are refused by name when the config is loaded (one check a test)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bimkit.errors import InputError
from initcli.config import parse_config
from initcli.config.checks import CHECKS, given_paths


def _refused(doc: dict, pattern: str, source: Path | None = None) -> None:
    with pytest.raises(InputError, match=pattern) as info:
        parse_config({"site": {"path": "x.ifc"}, **doc}, source)
    assert "\n" not in str(info.value)


def _accepted(doc: dict, source: Path | None = None) -> None:
    parse_config({"site": {"path": "x.ifc"}, **doc}, source)


def test_defaults_pass_every_check() -> None:
    _accepted({})
    assert len(CHECKS) >= 8


def test_given_paths_are_the_dotted_keys_a_file_sets() -> None:
    assert given_paths({"sim": {"miss_rate": 0.1, "detector": {"profile": "x"}}}) == {
        "sim",
        "sim.miss_rate",
        "sim.detector",
        "sim.detector.profile",
    }


def test_min_depth_above_max_depth() -> None:
    _refused(
        {"matching": {"min_depth": 5, "max_depth": 2}},
        r"matching.min_depth \(5 m\) must be below matching.max_depth \(2 m\)",
    )
    _refused({"matching": {"min_depth": 2, "max_depth": 2}}, r"matching.min_depth")
    _accepted({"matching": {"min_depth": 1, "max_depth": 2}})


def test_principal_point_outside_the_image() -> None:
    _refused(
        {"camera": {"cx": 2000}}, r"camera.cx \(2000 px\) lies outside the image \(camera.width 640 px\)"
    )
    _refused(
        {"camera": {"cy": 3000}}, r"camera.cy \(3000 px\) lies outside the image \(camera.height 480 px\)"
    )
    _refused({"camera": {"width": 300, "height": 240}}, r"camera.cx \(320 px\)")  # the default cx 320
    _accepted({"camera": {"width": 320, "height": 240, "cx": 160, "cy": 120}})


def test_camera_min_range_at_or_above_its_range() -> None:
    _refused({"camera": {"min_range": 6, "range": 6}}, r"camera.min_range \(6 m\) must be below camera.range")


def test_p_right_above_p_wrong() -> None:
    _refused(
        {"verification": {"p_right": 0.95}},
        r"verification.p_right \(0.95\) is above verification.p_wrong \(0.9\)",
    )
    _accepted({"verification": {"p_right": 0.9}})


def test_wall_distance_within_the_robot() -> None:
    _refused(
        {"robot": {"radius": 1.0}}, r"exploration.wall_distance \(0.7 m\) must be above robot.radius \(1 m\)"
    )
    _accepted({"robot": {"radius": 1.0}, "exploration": {"wall_distance": 1.3}})


def test_fine_tuning_that_could_never_converge() -> None:
    _refused(
        {"fine_tuning": {"min_travel": 8}},
        r"fine_tuning.min_travel \(8 m\) is above fine_tuning.distance \(6 m\)",
    )
    _accepted({"fine_tuning": {"min_travel": 8, "enabled": False}})


def test_physical_bounds_in_the_settings() -> None:
    _refused({"robot": {"radius": 5}}, r"robot.radius: 5 is above the maximum 2")
    _refused({"lidar": {"max_range": 0.01}}, r"lidar.max_range: 0.01 is below the minimum 1")


def test_a_profile_with_the_flat_rates_it_replaces_is_refused() -> None:
    both = {"sim": {"miss_rate": 0.1, "confusion_rate": 0.02, "detector": {"profile": "default-real"}}}
    _refused(both, r"sim.detector.profile replaces sim.miss_rate, sim.confusion_rate: set the profile or")
    _accepted({"sim": {"detector": {"profile": "default-real"}}})
    _accepted({"sim": {"miss_rate": 0.3}})  # the flat rates alone, as before


def test_a_profile_with_the_onnx_detector_is_refused() -> None:
    doc = {"detector": {"kind": "onnx"}, "sim": {"detector": {"profile": "default-renders"}}}
    _refused(doc, r"sim.detector.profile is for detector.kind simulated")


def test_a_profile_that_is_missing_or_broken_is_refused_before_anything_runs(tmp_path: Path) -> None:
    source = tmp_path / "site.yaml"
    _refused(
        {"sim": {"detector": {"profile": "mine.json"}}}, r"sim.detector.profile: .*mine.json: no such", source
    )
    (tmp_path / "bad.json").write_text(json.dumps({"format": "bim-init.detector-profile/1"}))
    _refused(
        {"sim": {"detector": {"profile": "bad.json"}}},
        r"sim.detector.profile: .*bad.json: .*required",
        source,
    )


def test_the_onnx_detector_without_onnxruntime_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """onnxruntime is the [detector] extra: a config that needs it says how to install it."""
    from initcli.config import checks

    monkeypatch.setattr(checks, "RUNTIME_AVAILABLE", False)
    _refused({"detector": {"kind": "onnx"}}, r"detector.kind onnx runs .* pip install 'bim-init\[detector\]'")
    _accepted({"detector": {"kind": "simulated"}})
