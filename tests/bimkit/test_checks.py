"""bimkit.checks: number ranges, text and YAML files, the option callback."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import pytest
import typer

from bimkit.checks import (
    check_finite_tree,
    check_number,
    parse_yaml,
    range_problem,
    read_text,
    read_yaml,
    show_number,
)
from bimkit.cli import number_option
from bimkit.errors import EXIT_BAD_INPUT, InputError


@pytest.mark.parametrize(
    ("value", "shown"),
    [(True, "true"), (False, "false"), (12, "12"), (3.0, "3"), (1e12, "1000000000000"), (1e-9, "1e-09")],
)
def test_show_number_writes_numbers_as_a_user_would(value: float, shown: str) -> None:
    assert show_number(value) == shown


def test_show_number_nan_and_huge_floats_keep_repr() -> None:
    assert show_number(math.nan) == "nan"
    assert show_number(1e20) == repr(1e20)


def test_range_problem_inclusive_and_exclusive_bounds() -> None:
    assert range_problem(0.0, minimum=0.0) is None
    assert range_problem(-0.1, minimum=0.0) == "-0.1 is below the minimum 0"
    assert range_problem(0.0, above=0.0) == "0 must be > 0"
    assert range_problem(10, maximum=10) is None
    assert range_problem(11, maximum=10) == "11 is above the maximum 10"
    assert range_problem(1.0, below=1.0) == "1 must be < 1"
    assert range_problem(0.5, above=0.0, below=1.0) is None


def test_range_problem_rejects_non_numbers_and_non_finite() -> None:
    assert range_problem(True) == "expected a number, got True"
    assert range_problem("3") == "expected a number, got '3'"
    assert range_problem(math.inf) == "inf is not a finite number"
    assert range_problem(math.nan, minimum=0) == "nan is not a finite number"


def test_check_number_returns_value_or_names_the_option() -> None:
    assert check_number(0.05, "--resolution", minimum=0.005) == 0.05
    with pytest.raises(InputError, match=r"^--resolution: 0 is below the minimum 0.005$"):
        check_number(0.0, "--resolution", minimum=0.005)


def test_check_finite_tree_names_the_yaml_path() -> None:
    check_finite_tree({"a": [1, 2.5, {"b": "x"}]}, "cfg.yaml")
    with pytest.raises(InputError, match=r"^cfg.yaml: a.2.b: inf is not a finite number$"):
        check_finite_tree({"a": [1, 2.5, {"b": math.inf}]}, "cfg.yaml")
    with pytest.raises(InputError, match=r"\(top level\): nan"):
        check_finite_tree(math.nan, "cfg.yaml")


def test_read_text_errors(tmp_path: Path) -> None:
    good = tmp_path / "good.txt"
    good.write_text("héllo\n", encoding="utf-8")
    assert read_text(good, "a log") == "héllo\n"
    with pytest.raises(InputError, match="cannot read a log: No such file"):
        read_text(tmp_path / "missing.txt", "a log")
    with pytest.raises(InputError, match="is a folder, expected a log"):
        read_text(tmp_path, "a log")
    binary = tmp_path / "bin.dat"
    binary.write_bytes(b"abc\x00def")
    with pytest.raises(InputError, match="not a text file"):
        read_text(binary, "a log")
    latin = tmp_path / "latin.txt"
    latin.write_bytes(b"line one\nline two\ncaf\xe9\n")
    with pytest.raises(InputError, match=r"latin.txt:3: not UTF-8 text"):
        read_text(latin, "a log")


def test_parse_yaml_reads_exponents_as_numbers_and_names_the_bad_line() -> None:
    doc = parse_yaml("a: 1e12\nb: 2.5e-3\nc: 1_0\nd: text\n", "x.yaml", "a config")
    assert doc["a"] == 1e12 and isinstance(doc["a"], float)
    assert doc["b"] == pytest.approx(2.5e-3)
    assert doc["d"] == "text"
    with pytest.raises(InputError, match=r"^x.yaml:2: invalid YAML in a config"):
        parse_yaml("a: 1\nb: c: d\n", "x.yaml", "a config")


def test_read_yaml_refuses_non_finite_numbers(tmp_path: Path) -> None:
    path = tmp_path / "cfg.yaml"
    path.write_text("fine_tuning:\n  particles: 100\n", encoding="utf-8")
    assert read_yaml(path, "a config") == {"fine_tuning": {"particles": 100}}
    path.write_text("fine_tuning:\n  sigma: .nan\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"fine_tuning.sigma: nan is not a finite number"):
        read_yaml(path, "a config")


def test_number_option_callback_exits_2_with_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    callback = number_option("bim-extract", minimum=0.005, maximum=1.0)
    ctx = SimpleNamespace(resilient_parsing=False)
    param = SimpleNamespace(opts=["-r", "--resolution"], name="resolution")
    assert callback(ctx, param, 0.05) == 0.05
    assert callback(ctx, param, None) is None
    assert callback(SimpleNamespace(resilient_parsing=True), param, math.nan) is math.nan
    with pytest.raises(typer.Exit) as caught:
        callback(ctx, param, [0.1, 2.0])
    assert caught.value.exit_code == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err == "bim-extract: error: --resolution: 2 is above the maximum 1\n"
