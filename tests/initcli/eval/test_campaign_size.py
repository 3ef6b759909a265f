"""The size of an evaluation campaign, known from its config before any site is prepared."""

from __future__ import annotations

from pathlib import Path

from initcli.eval.campaign import trial_count
from initcli.eval.config import EvalConfig, EvalSite
from initcli.eval.sweep import parse_sweep


def _config() -> EvalConfig:
    return EvalConfig(
        sites=[
            EvalSite("a", Path("a.yaml"), starts=100),
            EvalSite("b", Path("b.yaml"), starts=5, start_poses=[(0.0, 0.0, 0.0)] * 5),
        ]
    )


def test_trials_are_starts_times_methods_times_sweep_values() -> None:
    size = trial_count(_config(), ("bim", "amcl"))
    assert (size.trials, size.starts, size.sites, size.methods, size.values) == (210, 105, 2, 2, 1)
    assert str(size) == "210 trials (105 starts over 2 site(s) x 2 method(s))"
    swept = trial_count(_config(), ("bim",), starts=3, sweep=parse_sweep("alpha=1,2,3,4"))
    assert swept.trials == (3 + 3) * 4  # --starts caps the explicit start poses too
    assert "x 4 sweep values" in str(swept)
    assert trial_count(_config(), ("bim",), only=["b"]).trials == 5
