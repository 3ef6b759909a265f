"""Settings records: the schema, range checks and defaults are derived from each field, written once."""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass

import jsonschema
import pytest

from bimkit.errors import InputError
from bimkit.settings import check_ranges, meta_of, range_text, schema_of, section, setting, shared
from initcli.config import SCHEMA_PATH, SessionConfig, site_config_schema


@dataclass
class Inner:
    reach: float = setting(2.0, "m: how far", above=0, maximum=10)


GAP = shared(0.5, "m: a gap", minimum=0)


@dataclass
class Outer:
    name: str = setting("", "a name", required=True)
    count: int = setting(3, "things counted", above=0, maximum=8)
    share: float = setting(0.25, "a share", minimum=0, below=1)
    mode: str = setting("a", "a mode", enum=("a", "b"))
    on: bool = setting(True, "a switch")
    names: dict[str, str] = setting({}, "a mapping")
    gap: float = GAP()
    inner: Inner = section(Inner, "the inner part")
    plain: int = 7  # not a setting: left out


def test_a_record_becomes_a_closed_object_schema_with_every_setting_and_range() -> None:
    schema = schema_of(Outer)
    assert schema["additionalProperties"] is False and schema["required"] == ["name"]
    props = schema["properties"]
    assert set(props) == {"name", "count", "share", "mode", "on", "names", "gap", "inner"}
    assert props["count"] == {
        "type": "integer",
        "default": 3,
        "exclusiveMinimum": 0,
        "maximum": 8,
        "description": "things counted, 1-8",
    }
    assert props["share"]["exclusiveMaximum"] == 1 and props["share"]["description"] == "a share, [0, 1)"
    assert props["mode"]["enum"] == ["a", "b"] and props["on"]["type"] == "boolean"
    assert props["names"] == {
        "type": "object",
        "additionalProperties": {"type": "string"},
        "default": {},
        "description": "a mapping",
    }
    assert props["gap"]["description"] == "m: a gap, >= 0"
    inner = props["inner"]
    assert inner["description"] == "the inner part" and inner["properties"]["reach"]["default"] == 2.0
    assert "default" not in inner  # a section is no leaf
    validator = jsonschema.Draft202012Validator(schema)
    assert validator.is_valid({"name": "x", "count": 8, "inner": {"reach": 10}})
    for bad in ({}, {"name": "x", "count": 0}, {"name": "x", "share": 1}, {"name": "x", "inner": {"r": 1}}):
        assert not validator.is_valid(bad), bad


def test_mutable_defaults_are_copied_per_record() -> None:
    a, b = Outer(), Outer()
    a.names["door"] = "Door"
    assert b.names == {}


def test_range_text_reads_as_a_reader_writes_ranges() -> None:
    @dataclass
    class R:
        a: float = setting(1.0, "", above=0, maximum=5)
        b: float = setting(1.0, "", minimum=-1, maximum=1)
        c: float = setting(1.0, "", maximum=3)
        d: float = setting(1.0, "")

    metas = [meta_of(f) for f in dataclasses.fields(R)]
    assert [range_text(m) for m in metas if m is not None] == ["(0, 5]", "[-1, 1]", "<= 3", ""]


def test_check_ranges_names_the_setting_out_of_range() -> None:
    check_ranges(Outer())  # the defaults are within their ranges
    with pytest.raises(InputError, match=r"^--count: 9 is above the maximum 8$"):
        check_ranges(dataclasses.replace(Outer(), count=9), lambda n: f"--{n}")
    with pytest.raises(InputError, match="share: nan is not a finite number"):
        check_ranges(dataclasses.replace(Outer(), share=math.nan))
    with pytest.raises(InputError, match="mode: expected one of a, b, got 'c'"):
        check_ranges(dataclasses.replace(Outer(), mode="c"))


def test_the_committed_site_config_schema_is_the_generated_one() -> None:
    """``bimkit/schemas/site_config.schema.json`` is written by ``python -m initcli.config --write``
    (``make schemas``) from the records: a setting added, removed or changed without regenerating it
    fails here."""
    generated = json.dumps(site_config_schema(), indent=2) + "\n"
    assert SCHEMA_PATH.read_text(encoding="utf-8") == generated, "run `make schemas`"
    jsonschema.Draft202012Validator.check_schema(site_config_schema())


def test_every_session_config_field_is_a_setting_with_a_description() -> None:
    """A record field declared without :func:`setting` would be missing from the schema (and so be
    refused in site.yaml): every field of every section is one, and says what it is."""

    def walk(record: type, where: str) -> int:
        count = 0
        for f in dataclasses.fields(record):
            meta = meta_of(f)
            if record is SessionConfig and f.name == "source":
                continue
            assert meta is not None, f"{where}{f.name}"
            if dataclasses.is_dataclass(f.type) or f.default_factory is not dataclasses.MISSING:
                value = f.default_factory() if f.default_factory is not dataclasses.MISSING else None
                if dataclasses.is_dataclass(value):
                    count += walk(type(value), f"{where}{f.name}.")
                    continue
            assert meta.doc, f"{where}{f.name} has no description"
            count += 1
        return count

    assert walk(SessionConfig, "") > 150
