"""read_json: the document, or one InputError naming the file, the line and the problem."""

from __future__ import annotations

import pytest

from bimkit.checks import read_json
from bimkit.errors import InputError


def test_reads_the_document(tmp_path):
    path = tmp_path / "site.json"
    path.write_text('{"a": [1, 2.5, "é"]}', encoding="utf-8")
    assert read_json(path) == {"a": [1, 2.5, "é"]}


def test_bad_json_names_the_line(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{\n  "a": 1,\n  "b": \n}\n')
    with pytest.raises(InputError, match=r"bad\.json:4: not valid JSON: Expecting value"):
        read_json(path)


def test_missing_file_is_one_error(tmp_path):
    with pytest.raises(InputError, match=r"nope\.json: cannot read a JSON file: No such file"):
        read_json(tmp_path / "nope.json")
