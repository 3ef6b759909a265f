"""Property-based: every file reader, fed mutated and random files, reads them or raises one
InputError of one line, never another exception (a few examples each here; ``make fuzz`` runs each
target for longer)."""

from __future__ import annotations

from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.fuzz.targets import SITE_YAML, TARGETS, Target, target

SUITE = settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck), database=None)


@pytest.mark.parametrize("name", [t.name for t in TARGETS])
def test_the_valid_file_is_read(name: str) -> None:
    """The seed itself passes: a target whose valid file were refused would prove nothing."""
    chosen = target(name)
    chosen.check(chosen.seed())  # no InputError expected: check that it reads it
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        for other, content in chosen.beside().items():
            (Path(tmp) / other).write_bytes(content)
        (Path(tmp) / chosen.file).write_bytes(chosen.seed())
        chosen.read(Path(tmp) / chosen.file)


def _fuzz(chosen: Target):
    @SUITE
    @given(chosen.strategy())
    def run(data: bytes) -> None:
        chosen.check(data)

    return run


@pytest.mark.parametrize("name", [t.name for t in TARGETS])
def test_a_mutated_file_is_read_or_refused_in_one_line(name: str) -> None:
    _fuzz(target(name))()


YAML_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
    max_leaves=10,
)
SECTIONS = [
    "site",
    "robot",
    "camera",
    "lidar",
    "detector",
    "matching",
    "exploration",
    "fine_tuning",
    "limits",
    "sim",
]


@SUITE
@given(st.sampled_from(SECTIONS), st.text(max_size=12), YAML_VALUES)
def test_site_config_with_random_values(section: str, key: str, value: Any) -> None:
    """Any value at any key of a valid config: a config or InputError."""
    doc = yaml.safe_load(SITE_YAML)
    doc.setdefault(section, {})
    if isinstance(doc[section], dict):
        known = list(doc[section]) or [key]
        doc[section][known[hash(key) % len(known)] if key[:1] != "x" else key] = value
    target("site-config").check(yaml.safe_dump(doc).encode("utf-8"))


@SUITE
@given(st.sampled_from(["failure", "amcl", "markers", "starts", "seed", "sites"]), YAML_VALUES)
def test_eval_config_with_random_values(key: str, value: Any) -> None:
    doc = yaml.safe_load(target("eval-config").seed())
    doc[key] = value
    target("eval-config").check(yaml.safe_dump(doc).encode("utf-8"))
