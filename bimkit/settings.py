"""Settings records: every tunable written once, as a typed dataclass field that carries its one
default, its unit and its range.

A record is a plain dataclass whose fields are declared with :func:`setting` (a value) or
:func:`section` (a nested record)::

    @dataclass
    class LoopSettings:
        window: float = setting(45.0, "s of path checked for a loop", above=0, maximum=3600)

Everything else is derived from those fields: the JSON Schema of the site config
(:func:`schema_of`; ``python -m initcli.config --write`` regenerates
``bimkit/schemas/site_config.schema.json``, and a test fails when the committed file differs),
the range checks of a record built in code (:func:`check_ranges`, used for ``bim-init match``'s
options) and the command-line options of ``bim-init match`` (``metavar`` and ``flag``). The bounds
are JSON Schema's: ``minimum``/``maximum`` inclusive, ``above``/``below`` exclusive
(``exclusiveMinimum``/``exclusiveMaximum``). The standard library only at import: the records of
:mod:`initcli.core` declare their fields with it too.
"""

from __future__ import annotations

import copy
import dataclasses
import types
import typing
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

__all__ = [
    "Meta",
    "check_ranges",
    "describe",
    "meta_of",
    "range_text",
    "schema_of",
    "section",
    "setting",
    "settings_of",
    "shared",
]

_KEY = "bim-init setting"  # the key of a field's metadata that holds its Meta


@dataclass(frozen=True)
class Meta:
    """What a setting is, beyond its type and default."""

    doc: str  # what it does, starting with its unit (``m: ...``, ``s of ...``, ``share of ...``)
    minimum: float | None = None
    maximum: float | None = None
    above: float | None = None  # exclusive minimum
    below: float | None = None  # exclusive maximum
    enum: tuple[str, ...] | None = None
    required: bool = False
    schema: Mapping[str, Any] | None = None  # a JSON Schema of its own (no type derived)
    metavar: str | None = None  # an option of ``bim-init match`` with this value name ...
    flag: str | None = None  # ... or a switch declared so (``--revisits/--no-revisits``)

    def bounds(self) -> dict[str, float]:
        """The bounds as :func:`bimkit.checks.check_number` takes them (those that are set)."""
        given = {"minimum": self.minimum, "maximum": self.maximum, "above": self.above, "below": self.below}
        return {k: v for k, v in given.items() if v is not None}


def setting(
    default: Any,
    doc: str,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
    enum: tuple[str, ...] | None = None,
    required: bool = False,
    schema: Mapping[str, Any] | None = None,
    metavar: str | None = None,
    flag: str | None = None,
) -> Any:
    """A dataclass field holding one setting: its default (a mutable one is copied per record),
    ``doc`` (unit first) and its range."""
    meta = Meta(doc, minimum, maximum, above, below, enum, required, schema, metavar, flag)
    if isinstance(default, dict | list):
        return dataclasses.field(default_factory=lambda: copy.deepcopy(default), metadata={_KEY: meta})
    return dataclasses.field(default=default, metadata={_KEY: meta})


def shared(default: Any, doc: str, **bounds: Any) -> Callable[[], Any]:
    """One setting declared in several records (the same name, unit, range and default in each):
    ``D_THRE = shared(0.5, "m: ...", minimum=0)``, then ``d_thre: float = D_THRE()`` in each."""
    return lambda: setting(default, doc, **bounds)


def section(record: type, doc: str = "", required: bool = False) -> Any:
    """A dataclass field holding a nested record (a section of the site config)."""
    return dataclasses.field(default_factory=record, metadata={_KEY: Meta(doc, required=required)})


def meta_of(f: dataclasses.Field[Any]) -> Meta | None:
    """The :class:`Meta` of a field declared with :func:`setting` or :func:`section` (else None)."""
    return f.metadata.get(_KEY)


def settings_of(record: type | object) -> Iterator[tuple[dataclasses.Field[Any], Meta, Any]]:
    """Each field of ``record`` declared as a setting or section, its :class:`Meta` and its type."""
    cls = record if isinstance(record, type) else type(record)
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        meta = meta_of(f)
        if meta is not None:
            yield f, meta, hints[f.name]


def _default(f: dataclasses.Field[Any]) -> Any:
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return f.default


def _base(tp: Any) -> Any:
    """``float | None`` -> ``float``; other types as they are."""
    if isinstance(tp, types.UnionType) or typing.get_origin(tp) is typing.Union:
        rest = [a for a in typing.get_args(tp) if a is not type(None)]
        return rest[0] if len(rest) == 1 else tp
    return tp


def _json_type(tp: Any) -> dict[str, Any]:
    tp = _base(tp)
    if tp is bool:
        return {"type": "boolean"}
    if tp is int:
        return {"type": "integer"}
    if tp is float:
        return {"type": "number"}
    if tp is str:
        return {"type": "string"}
    if typing.get_origin(tp) is dict and typing.get_args(tp)[1:] == (str,):
        return {"type": "object", "additionalProperties": {"type": "string"}}
    raise TypeError(f"no JSON Schema type for {tp!r}: give the setting a schema of its own")


def range_text(meta: Meta, integer: bool = False) -> str:
    """The range of a setting as a reader writes it: ``(0, 5]``, ``[0, 1]``, ``1-8192``, ``>= 0``."""
    from bimkit.checks import show_number

    lo, lo_open = (meta.above, True) if meta.above is not None else (meta.minimum, False)
    hi, hi_open = (meta.below, True) if meta.below is not None else (meta.maximum, False)
    if lo is None and hi is None:
        return ""
    if integer and lo is not None and hi is not None:
        first = int(lo) + 1 if lo_open else int(lo)
        last = int(hi) - 1 if hi_open else int(hi)
        return f"{first}-{last}"
    if lo is None:
        return f"{'<' if hi_open else '<='} {show_number(hi)}"  # type: ignore[arg-type]
    if hi is None:
        return f"{'>' if lo_open else '>='} {show_number(lo)}"
    return f"{'(' if lo_open else '['}{show_number(lo)}, {show_number(hi)}{')' if hi_open else ']'}"


def describe(meta: Meta, integer: bool = False) -> str:
    """A setting's description with its range appended (the schema's and the option's help)."""
    text = range_text(meta, integer)
    return f"{meta.doc}, {text}" if text else meta.doc


def schema_of(record: type, doc: str = "") -> dict[str, Any]:
    """The JSON Schema of a record: an object of its settings, no other key allowed, each setting
    with its type, default, allowed values, bounds and description (range appended)."""
    properties: dict[str, Any] = {}
    required: list[str] = []
    for f, meta, tp in settings_of(record):
        if dataclasses.is_dataclass(tp):
            properties[f.name] = schema_of(tp, meta.doc)  # type: ignore[arg-type]
        else:
            node: dict[str, Any] = dict(meta.schema) if meta.schema is not None else _json_type(tp)
            node["default"] = _default(f)
            if meta.enum is not None:
                node["enum"] = list(meta.enum)
            keywords = {"minimum": "minimum", "above": "exclusiveMinimum"}
            keywords |= {"maximum": "maximum", "below": "exclusiveMaximum"}
            for name, value in meta.bounds().items():
                node[keywords[name]] = value
            description = describe(meta, node.get("type") == "integer")
            if description:
                node["description"] = description
            properties[f.name] = node
        if meta.required:
            required.append(f.name)
    out: dict[str, Any] = {"type": "object", "additionalProperties": False}
    if doc:
        out["description"] = doc
    out["properties"] = properties
    if required:
        out["required"] = required
    return out


def check_ranges(record: object, name: Callable[[str], str] = str) -> None:
    """Every setting of ``record`` (a record built in code, not read from a file) within its range
    and among its allowed values; else one :class:`~bimkit.errors.InputError` naming it as
    ``name(field)``."""
    from bimkit.checks import check_number
    from bimkit.errors import InputError

    for f, meta, _ in settings_of(record):
        value = getattr(record, f.name)
        if value is None or dataclasses.is_dataclass(value):
            continue
        if meta.enum is not None and value not in meta.enum:
            raise InputError(f"{name(f.name)}: expected one of {', '.join(meta.enum)}, got {value!r}")
        bounds = meta.bounds()
        if bounds or (isinstance(value, float) and not isinstance(value, bool)):
            check_number(value, name(f.name), **bounds)
