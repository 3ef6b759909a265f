"""initcli.eval.config: an eval.yaml's site configs are named by their entry when they cannot be read."""

from __future__ import annotations

from pathlib import Path

import pytest

from bimkit.errors import InputError
from initcli.eval.config import load_eval_config


@pytest.mark.parametrize(
    ("config", "said"),
    [
        ("9" * 3000 + "site.yaml", r"eval.yaml: sites.0.config: File name too long$"),
        ("absent.yaml", r"eval.yaml: sites.0.config: .*absent.yaml does not exist$"),
    ],
    ids=["name too long", "absent"],
)
def test_a_site_config_that_cannot_be_found_is_named_by_its_entry(
    tmp_path: Path, config: str, said: str
) -> None:
    (tmp_path / "eval.yaml").write_text(f"sites:\n  - config: {config}\nstarts: 2\n")
    with pytest.raises(InputError, match=said):
        load_eval_config(tmp_path / "eval.yaml")
