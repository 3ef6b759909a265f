"""Without --config, bim-init eval uses the source tree's sample config, or says to pass one."""

from __future__ import annotations

from pathlib import Path

import pytest

import initcli.eval.config as eval_config
from bimkit.errors import InputError


def test_default_config_is_the_source_trees_sample() -> None:
    config = eval_config.load_eval_config(None)
    assert config.source == eval_config.DEFAULT_CONFIG and len(config.sites) == 3


def test_missing_default_config_asks_for_config(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(eval_config, "DEFAULT_CONFIG", tmp_path / "sample_models" / "eval.yaml")
    with pytest.raises(InputError, match="pass --config"):
        eval_config.load_eval_config(None)
