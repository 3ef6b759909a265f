"""Sweep parsing and application to a session config."""

from __future__ import annotations

import pytest

from bimkit.errors import InputError
from initcli.config import SessionConfig
from initcli.eval.sweep import apply_sweep, parse_sweep
from initcli.match.pipeline import MatchOptions


def test_short_names_map_to_config_paths():
    assert parse_sweep("miss_rate=0,0.25,0.5").path == "sim.miss_rate"
    assert parse_sweep("beta=10,20").values == (10.0, 20.0)
    assert parse_sweep("camera.range=4,8").path == "camera.range"


def test_apply_sets_one_value_and_leaves_the_original_alone():
    config = SessionConfig()
    swept = apply_sweep(config, parse_sweep("alpha=1.1"), 1.1)
    assert swept.matching.alpha == 1.1 and config.matching.alpha == MatchOptions().alpha
    assert swept.matching.beta == config.matching.beta
    people = apply_sweep(config, parse_sweep("people=0,4"), 4.0)
    assert people.sim.people == 4 and isinstance(people.sim.people, int)
    old = apply_sweep(config, parse_sweep("workers=0,3"), 3.0)  # the former name of the key
    assert old.sim.people == 3


def test_odometry_drift_scales_every_alpha():
    config = SessionConfig()
    swept = apply_sweep(config, parse_sweep("odometry_drift=1,3"), 3.0)
    before, after = config.sim.odometry_noise, swept.sim.odometry_noise
    for name in ("alpha1", "alpha2", "alpha3", "alpha4"):
        assert getattr(after, name) == pytest.approx(3 * getattr(before, name))


@pytest.mark.parametrize("text", ["nope=1", "sim.nothing=1", "detector.kind=1", "=1", "alpha="])
def test_bad_sweeps_are_input_errors(text):
    with pytest.raises(InputError):
        parse_sweep(text)


def test_swept_values_pass_the_config_checks_before_any_trial():
    from initcli.eval.sweep import check_sweep

    config = SessionConfig()
    check_sweep(parse_sweep("matching.min_depth=0.2,1"), [config])
    with pytest.raises(
        InputError, match=r"--sweep matching.min_depth=20: matching.min_depth \(20 m\) must be below"
    ):
        check_sweep(parse_sweep("matching.min_depth=1,20"), [config])
    config.sim.detector.profile = "default-real"
    with pytest.raises(
        InputError, match=r"--sweep miss_rate=0.2: sim.detector.profile replaces sim.miss_rate"
    ):
        check_sweep(parse_sweep("miss_rate=0.2"), [config])
