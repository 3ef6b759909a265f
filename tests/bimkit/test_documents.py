"""bimkit.documents: bounded reading -- no device or pipe, no file past its limit, no YAML alias bomb,
no duplicate key, no integer of thousands of digits, no JSON nested past the limit, no NaN."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from bimkit.documents import open_input, parse_json, parse_yaml, read_bytes, read_json, read_text, read_yaml
from bimkit.errors import InputError
from bimkit.limits import MAX_DEPTH, MAX_INT_DIGITS, show_bytes

BILLION_LAUGHS = "\n".join(
    ["a: &a [x, x, x, x, x, x, x, x, x]"]
    + [f"{chr(98 + k)}: &{chr(98 + k)} [{', '.join([f'*{chr(97 + k)}'] * 9)}]" for k in range(8)]
)


def test_a_device_or_a_pipe_is_refused_at_once(tmp_path: Path) -> None:
    started = time.monotonic()
    with pytest.raises(InputError, match=r"^/dev/zero: is a device, expected a config \(a regular file\)$"):
        read_text(Path("/dev/zero"), "a config")
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match=r"fifo: is a pipe \(FIFO\), expected a log"):
        read_bytes(fifo, "a log", 100)
    assert time.monotonic() - started < 5


def test_a_file_past_its_limit_is_refused_before_it_is_read(tmp_path: Path) -> None:
    big = tmp_path / "big.yaml"
    big.write_bytes(b"a: 1\n" * 1000)
    with pytest.raises(InputError, match=r"big.yaml: 4.9 KiB is above the limit of 1 KiB for a config"):
        read_yaml(big, "a config", limit=1024)
    assert show_bytes(2 << 30) == "2 GiB" and show_bytes(100) == "100 bytes"
    os.close(open_input(big, "a config", 1 << 20))
    with pytest.raises(InputError, match="is a folder, expected a config"):
        open_input(tmp_path, "a config", 10)


def test_a_pseudo_file_that_reports_no_size_is_cut_at_the_limit() -> None:
    with pytest.raises(InputError, match=r"more than the limit of 16 bytes"):
        read_bytes(Path("/proc/self/status"), "a log", 16)


def test_a_billion_laughs_is_refused_quickly() -> None:
    started = time.monotonic()
    with pytest.raises(InputError, match=r"^c.yaml: its aliases would expand it by \d+ nodes .*alias bomb"):
        parse_yaml(BILLION_LAUGHS, "c.yaml", "a config")
    assert time.monotonic() - started < 2


def test_a_few_aliases_are_fine_and_a_recursive_one_is_refused() -> None:
    doc = parse_yaml("base: &b {x: 1, y: 2}\none: *b\ntwo: {<<: *b, y: 3}\n", "c.yaml", "a config")
    assert doc == {"base": {"x": 1, "y": 2}, "one": {"x": 1, "y": 2}, "two": {"x": 1, "y": 3}}
    with pytest.raises(InputError, match=r"^c.yaml:1: a recursive alias"):
        parse_yaml("a: &a [1, *a]\n", "c.yaml", "a config")


def test_duplicate_keys_are_refused_with_the_line() -> None:
    with pytest.raises(
        InputError, match=r"^c.yaml:3: duplicate key 'site' \(the later one would silently win\)"
    ):
        parse_yaml("site:\n  path: a.ifc\nsite:\n  path: b.ifc\n", "c.yaml", "a site config")
    with pytest.raises(InputError, match=r"^c.yaml:3: duplicate key 'fx'"):
        parse_yaml("camera:\n  fx: 1\n  fx: 2\n", "c.yaml", "a site config")
    assert parse_yaml("a: {x: 1}\nb: {x: 2}\n", "c.yaml", "a config") == {"a": {"x": 1}, "b": {"x": 2}}


def test_long_integers_and_deep_nesting_are_refused() -> None:
    with pytest.raises(
        InputError, match=rf"^c.yaml:1: an integer of 5000 digits \(at most {MAX_INT_DIGITS}\)"
    ):
        parse_yaml("seed: " + "9" * 5000, "c.yaml", "a config")
    assert parse_yaml("seed: 4294967295", "c.yaml", "a config") == {"seed": 4294967295}
    with pytest.raises(InputError, match=rf"nested deeper than {MAX_DEPTH} levels"):
        parse_yaml("[" * 100 + "]" * 100, "c.yaml", "a config")
    with pytest.raises(InputError, match="nested deeper than"):
        parse_yaml("[" * 100_000, "c.yaml", "a config")


def test_json_limits_name_the_file_and_line() -> None:
    with pytest.raises(InputError, match=rf"^log.jsonl:7: JSON nested deeper than {MAX_DEPTH} levels$"):
        parse_json("[" * 100_000 + "]" * 100_000, "log.jsonl", line=7)
    with pytest.raises(InputError, match=rf"^log.jsonl:7: JSON nested deeper than {MAX_DEPTH} levels$"):
        parse_json("[" * 70 + "]" * 70, "log.jsonl", line=7)
    with pytest.raises(InputError, match=r"^s.json: an integer of 5000 digits"):
        parse_json('{"t": ' + "1" * 5000 + "}", "s.json")
    for text in ('{"x": NaN}', '{"x": [-Infinity]}', '{"x": {"y": 1e999}}'):
        with pytest.raises(InputError, match=r"^s.json: x(.0|.y)?: (nan|-?inf) is not a finite number$"):
            parse_json(text, "s.json")
    assert parse_json('{"x": NaN}', "s.json", finite=False)["x"] != 0
    with pytest.raises(InputError, match=r"^s.json:2: not valid JSON"):
        parse_json('{"a":\n}', "s.json")
    assert parse_json('{"a": [1, 2.5, -3e2]}', "s.json") == {"a": [1, 2.5, -300.0]}


def test_read_json_is_bounded_too(tmp_path: Path) -> None:
    path = tmp_path / "summary.json"
    path.write_text('{"success": true, "covariance": [[NaN]]}')
    with pytest.raises(InputError, match=r"summary.json: covariance.0.0: nan is not a finite number$"):
        read_json(path)
    with pytest.raises(InputError, match=r"^/dev/zero: is a device"):
        read_json(Path("/dev/zero"))
