"""bimkit.errors: one InputError type whose text is always one line."""

from __future__ import annotations

import yaml

from bimkit.errors import InputError
from tests.fuzz.targets import target


def test_a_line_break_in_the_input_stays_on_the_errors_one_line() -> None:
    exc = InputError("eval.yaml: amcl.\nx\r: unknown parameter")
    assert str(exc) == "eval.yaml: amcl.\\nx\\r: unknown parameter"
    assert exc.args == ("eval.yaml: amcl.\nx\r: unknown parameter",)


def test_an_eval_config_key_with_a_line_break_gives_one_line() -> None:
    """The fuzz finding: ``amcl: {"\\n": 0}`` named the key with its line break in the message."""
    doc = yaml.safe_load(target("eval-config").seed())
    doc["amcl"] = {"\n": 0}
    target("eval-config").check(yaml.safe_dump(doc).encode("utf-8"))
    doc["failure"] = {"\n": 0}
    target("eval-config").check(yaml.safe_dump(doc).encode("utf-8"))
