"""JSON Schemas of every file format bim-init reads or writes, shipped inside the package.

The top-level ``schemas/`` folder of the source tree is a link to this one: the published copy and
the packaged copy are the same files.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from bimkit.checks import check_finite_tree, range_problem
from bimkit.errors import InputError

__all__ = ["SCHEMA_DIR", "describe_value", "schema_path", "validate_document"]

SCHEMA_DIR = Path(__file__).resolve().parent


def schema_path(name: str) -> Path:
    """The packaged schema file ``name`` (for example ``"site_config.schema.json"``)."""
    return SCHEMA_DIR / name


def describe_value(value: Any) -> str:
    if isinstance(value, str):
        return json.dumps(value)
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    return repr(value)


_TYPE_WORDS = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "boolean": "true or false",
    "object": "a mapping",
    "array": "a list",
    "null": "null",
}


def _message(error: Any) -> tuple[str, str]:
    path = ".".join(str(p) for p in error.absolute_path)
    v = error.validator
    if v == "type":
        types = error.validator_value if isinstance(error.validator_value, list) else [error.validator_value]
        want = " or ".join(_TYPE_WORDS.get(str(t), str(t)) for t in types)
        return path, f"expected {want}, got {describe_value(error.instance)}"
    if v == "enum":
        return (
            path,
            f"expected one of {', '.join(map(str, error.validator_value))},"
            f" got {describe_value(error.instance)}",
        )
    if v in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
        bound = {"minimum": "minimum", "exclusiveMinimum": "above", "maximum": "maximum"}.get(v, "below")
        return path, range_problem(error.instance, **{bound: error.validator_value}) or error.message
    if v == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        where = f"{path}." if path else ""
        return f"{where}{extra[0]}" if extra else path, "unknown key (not in the config schema)"
    if v == "required":
        missing = [k for k in error.validator_value if k not in error.instance]
        where = f"{path}." if path else ""
        return f"{where}{missing[0]}" if missing else path, "required"
    if v in ("oneOf", "anyOf"):
        return (
            path,
            f"invalid value {describe_value(error.instance)}"
            f" ({error.schema.get('description', 'see schema')})",
        )
    return path, error.message


def validate_document(doc: Any, schema_path: Path, where: str) -> None:
    """Raise :class:`InputError` naming the YAML path of the deepest schema violation (NaN and
    infinity first: JSON Schema's ``number`` accepts them)."""
    import jsonschema  # at first use: a second at import for every command otherwise

    check_finite_tree(doc, where)
    schema = json.loads(schema_path.read_text(encoding="utf-8"))
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(
        validator.iter_errors(doc), key=lambda e: (len(list(e.absolute_path)), str(e.absolute_path))
    )
    if errors:
        error = max(errors, key=lambda e: len(list(e.absolute_path)))
        path, message = _message(error)
        raise InputError(f"{where}: {path or '(top level)'}: {message}")
