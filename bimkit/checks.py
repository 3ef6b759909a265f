"""The one validation layer at every way in: numbers, text, YAML and JSON documents, output folders.

Every check raises :class:`bimkit.errors.InputError` with a message that names the option, the
file and line or the YAML path, and what is wrong (``fine_tuning.particles: 1000000000000 is above
the maximum 200000``); the CLIs print it as one line on stderr and exit with code 2, before any
work starts. The ranges of the config files live in their JSON Schemas (``bimkit/schemas``);
the ranges of command-line options are given where each option is declared
(:func:`bimkit.cli.number_option`).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import yaml

from bimkit.errors import InputError

__all__ = [
    "check_finite_tree",
    "check_number",
    "check_output_dir",
    "check_output_file",
    "parse_yaml",
    "range_problem",
    "read_json",
    "read_text",
    "read_yaml",
    "show_number",
]


def show_number(value: float) -> str:
    """A number as the user would write it: ``1000000000000``, ``1e-09``, ``nan``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    return repr(value)


def range_problem(
    value: float,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
) -> str | None:
    """What is wrong with ``value`` (None when it is finite and within the bounds).

    ``minimum``/``maximum`` are inclusive, ``above``/``below`` exclusive (JSON Schema's
    ``exclusiveMinimum``/``exclusiveMaximum``).
    """
    shown = show_number(value)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"expected a number, got {value!r}"
    if isinstance(value, float) and not math.isfinite(value):
        return f"{shown} is not a finite number"
    if minimum is not None and value < minimum:
        return f"{shown} is below the minimum {show_number(minimum)}"
    if above is not None and value <= above:
        return f"{shown} must be > {show_number(above)}"
    if maximum is not None and value > maximum:
        return f"{shown} is above the maximum {show_number(maximum)}"
    if below is not None and value >= below:
        return f"{shown} must be < {show_number(below)}"
    return None


def check_number(
    value: float,
    name: str,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
) -> float:
    """``value`` when finite and within the bounds, else :class:`InputError` naming ``name``."""
    problem = range_problem(value, minimum=minimum, maximum=maximum, above=above, below=below)
    if problem is not None:
        raise InputError(f"{name}: {problem}")
    return value


def check_finite_tree(doc: Any, where: str, path: str = "") -> None:
    """Every number in a decoded YAML/JSON document is finite (JSON Schema's ``number`` accepts
    NaN and infinity, so the loaders call this before validating)."""
    if isinstance(doc, float) and not math.isfinite(doc):
        raise InputError(f"{where}: {path or '(top level)'}: {show_number(doc)} is not a finite number")
    if isinstance(doc, dict):
        for key, value in doc.items():
            check_finite_tree(value, where, f"{path}.{key}" if path else str(key))
    elif isinstance(doc, list):
        for index, value in enumerate(doc):
            check_finite_tree(value, where, f"{path}.{index}" if path else str(index))


# --- files -----------------------------------------------------------------------------------------


def read_text(path: Path, what: str, encoding: str = "utf-8") -> str:
    """The text of ``path``; a missing file, a folder or a binary file is one :class:`InputError`."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: cannot read {what}: No such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, expected {what}") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    if b"\x00" in data:
        raise InputError(f"{path}: not a text file ({what} expected, found binary data)")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise InputError(f"{path}:{line}: not UTF-8 text ({what} expected)") from None


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader, reading ``1e12`` as a number (YAML 1.2) rather than as text."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(
        r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
        |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
        |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
        |[-+]?\.(?:inf|Inf|INF)
        |\.(?:nan|NaN|NAN))$""",
        re.X,
    ),
    list("-+0123456789."),
)


def parse_yaml(text: str, where: str, what: str) -> Any:
    """The YAML document in ``text``; a syntax error names ``where`` and the line."""
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 (a SafeLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f":{mark.line + 1}" if mark is not None else ""
        raise InputError(f"{where}{line}: invalid YAML in {what} ({getattr(exc, 'problem', exc)})") from None
    except (RecursionError, ValueError, TypeError, OverflowError) as exc:  # pathological documents
        raise InputError(f"{where}: unreadable YAML in {what} ({type(exc).__name__})") from None


def read_yaml(path: Path, what: str) -> Any:
    """The YAML document at ``path``: decoded as UTF-8 text, parsed, every number finite."""
    path = Path(path)
    doc = parse_yaml(read_text(path, what), str(path), what)
    check_finite_tree(doc, str(path))
    return doc


def read_json(path: Path) -> Any:
    """The JSON document at ``path``: decoded as UTF-8 text, parsed, every number finite."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: cannot read: No such file")
    text = read_text(path, "a JSON file")
    try:
        doc = json.loads(text)
    except RecursionError:
        raise InputError(f"{path}: JSON nested too deeply") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}:{exc.lineno}: not valid JSON: {exc.msg}") from None
    check_finite_tree(doc, str(path))
    return doc


# --- output folders --------------------------------------------------------------------------------


def check_output_dir(path: Path, option: str, markers: Iterable[str], force: bool = False) -> None:
    """Refuse an output folder before any work starts.

    Writing over a file is refused; an existing folder is accepted when empty or when one of
    ``markers`` (the manifest or summary this tool writes) is in it (the run replaces it
    atomically); a folder with other content is refused unless ``force``.
    """
    path = Path(path)
    for parent in [path, *path.parents]:
        if parent.exists() and not parent.is_dir():
            what = "is a file" if parent == path else f"{parent} is a file"
            raise InputError(f"{option} {path}: {what}, expected a folder")
        if parent.exists():
            break
    if not path.is_dir() or force:
        return
    names = list(markers)
    try:
        contents = list(path.iterdir())
    except OSError as exc:
        raise InputError(f"{option} {path}: cannot read the folder: {exc.strerror or exc}") from None
    if not contents or any((path / m).is_file() for m in names):
        return
    raise InputError(
        f"{option} {path}: the folder exists and holds other files (no {' or '.join(names)} of an earlier "
        "run); pass --force to replace it"
    )


def check_output_file(path: Path, option: str) -> None:
    """An output file's path must not name a folder, and its parent must not be a file."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{option} {path}: is a folder, expected a file name")
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"{option} {path}: {parent} is a file, not a folder")
            break
