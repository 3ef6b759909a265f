"""Bounded reading of input files and of the YAML and JSON documents in them.

- :func:`open_input` / :func:`read_bytes` / :func:`read_text`: a regular file only (a device such as
  ``/dev/zero``, a pipe or a socket is refused at once: reading it could block or never end), at
  most a stated number of bytes (:mod:`bimkit.limits`), decoded as UTF-8;
- :func:`parse_yaml` / :func:`read_yaml`: PyYAML's safe loader, reading ``1e12`` as a number, with
  duplicate keys refused (the later one would silently win), integers of at most
  :data:`~bimkit.limits.MAX_INT_DIGITS` digits, nesting of at most :data:`~bimkit.limits.MAX_DEPTH`
  levels and aliases that may add at most :data:`~bimkit.limits.MAX_YAML_ALIAS_NODES` nodes (a
  "billion laughs" document is refused before it is expanded);
- :func:`parse_json` / :func:`read_json`: the same depth and digit limits, and no NaN or infinity
  anywhere (``NaN``, ``Infinity``, ``1e999``: refused naming their path in the document).

Every problem is one :class:`~bimkit.errors.InputError` naming the file (and line or path).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import stat
from pathlib import Path
from typing import Any

import yaml

from bimkit.errors import InputError
from bimkit.limits import MAX_DEPTH, MAX_INT_DIGITS, MAX_TEXT_BYTES, MAX_YAML_ALIAS_NODES, show_bytes

__all__ = [
    "check_finite_tree",
    "check_regular",
    "file_sha256",
    "open_input",
    "parse_json",
    "parse_yaml",
    "read_bytes",
    "read_json",
    "read_text",
    "read_yaml",
]


# --- files -----------------------------------------------------------------------------------------


def _kind(mode: int) -> str:
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISFIFO(mode):
        return "a pipe (FIFO)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def open_input(path: Path, what: str, limit: int) -> int:
    """An open file descriptor of the regular file ``path`` (at most ``limit`` bytes); a missing file,
    a folder, a device, a pipe or a file over the limit is one :class:`InputError`.

    Opened without blocking, so that a FIFO is refused rather than waited on."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise InputError(f"{path}: cannot read {what}: No such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, expected {what}") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise InputError(f"{path}: is a folder, expected {what}")
        if not stat.S_ISREG(info.st_mode):
            raise InputError(f"{path}: is {_kind(info.st_mode)}, expected {what} (a regular file)")
        if info.st_size > limit:
            raise InputError(
                f"{path}: {show_bytes(info.st_size)} is above the limit of {show_bytes(limit)} for {what}"
            )
    except BaseException:
        os.close(fd)
        raise
    return fd


def check_regular(path: Path, what: str, limit: int) -> None:
    """``path`` is a regular file of at most ``limit`` bytes (for a reader that opens it itself: a
    library, an image decoder); else one :class:`InputError`."""
    os.close(open_input(path, what, limit))


def read_bytes(path: Path, what: str, limit: int) -> bytes:
    """The bytes of the regular file ``path``, refused past ``limit`` bytes (a file that grows while
    it is read, or a pseudo-file that reports no size, is cut off at the limit, not read forever)."""
    fd = open_input(path, what, limit)
    with os.fdopen(fd, "rb") as handle:
        try:
            data = handle.read(limit + 1)
        except OSError as exc:
            raise InputError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise InputError(f"{path}: more than the limit of {show_bytes(limit)} for {what}")
    return data


def read_text(path: Path, what: str, encoding: str = "utf-8", limit: int = MAX_TEXT_BYTES) -> str:
    """The text of ``path``; a missing file, a folder, a device, a binary file or a file over
    ``limit`` bytes is one :class:`InputError`."""
    path = Path(path)
    data = read_bytes(path, what, limit)
    if b"\x00" in data:
        raise InputError(f"{path}: not a text file ({what} expected, found binary data)")
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise InputError(f"{path}:{line}: not UTF-8 text ({what} expected)") from None


# --- numbers ---------------------------------------------------------------------------------------


def _show(value: float) -> str:
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    return repr(value)


def check_finite_tree(doc: Any, where: str, path: str = "") -> None:
    """Every number in a decoded YAML/JSON document is finite (JSON Schema's ``number`` accepts
    NaN and infinity, so the loaders call this before validating). Walks without recursion: the
    documents of :func:`parse_yaml` and :func:`parse_json` are bounded in depth and size."""
    stack: list[tuple[Any, str]] = [(doc, path)]
    while stack:
        value, at = stack.pop()
        if isinstance(value, float) and not math.isfinite(value):
            raise InputError(f"{where}: {at or '(top level)'}: {_show(value)} is not a finite number")
        if isinstance(value, dict):
            items = list(value.items())
        elif isinstance(value, list):
            items = list(enumerate(value))
        else:
            continue
        stack.extend((v, f"{at}.{k}" if at else str(k)) for k, v in reversed(items))


# --- YAML ------------------------------------------------------------------------------------------


class _Limit(ValueError):
    """A document past one of the limits: ``line`` (1-based, 0 unknown) and the problem."""

    def __init__(self, problem: str, line: int = 0) -> None:
        super().__init__(problem)
        self.problem = problem
        self.line = line


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader reading ``1e12`` as a number (YAML 1.2) rather than as text, refusing
    duplicate keys, long integers, deep nesting and alias expansion past the budget."""

    def get_single_node(self) -> yaml.Node | None:
        node = super().get_single_node()
        if node is not None:
            _check_node_graph(node)
        return node

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge" or not isinstance(key_node, yaml.ScalarNode):
                continue
            key = self.construct_object(key_node)
            try:
                fresh = key not in seen
            except TypeError:  # an unhashable key: the constructor reports it
                continue
            if not fresh:
                raise _Limit(
                    f"duplicate key {key!r} (the later one would silently win)", key_node.start_mark.line + 1
                )
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def _bounded_int(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> int:
    digits = sum(c.isdigit() for c in str(node.value))
    if digits > MAX_INT_DIGITS:
        raise _Limit(f"an integer of {digits} digits (at most {MAX_INT_DIGITS})", node.start_mark.line + 1)
    return int(yaml.SafeLoader.construct_yaml_int(loader, node))


_Loader.add_constructor("tag:yaml.org,2002:int", _bounded_int)
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


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


def _check_node_graph(root: yaml.Node) -> None:
    """The composed document (aliases are shared nodes) expanded in the mind, without recursion:
    refuse a recursive alias, nesting past :data:`MAX_DEPTH` and aliases adding more than
    :data:`MAX_YAML_ALIAS_NODES` nodes. Linear in the document's text."""
    done: dict[int, tuple[int, int]] = {}  # id -> (expanded size, depth)
    open_: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, finished = stack.pop()
        key = id(node)
        if finished:
            open_.discard(key)
            kids = _children(node)
            size = 1 + sum(done[id(k)][0] for k in kids)
            depth = 1 + max((done[id(k)][1] for k in kids), default=0)
            if depth > MAX_DEPTH:
                raise _Limit(f"nested deeper than {MAX_DEPTH} levels", node.start_mark.line + 1)
            done[key] = (min(size, 1 << 62), depth)
            continue
        if key in done:
            continue
        open_.add(key)
        stack.append((node, True))
        for kid in _children(node):
            if id(kid) in open_:
                raise _Limit("a recursive alias (an anchor used inside itself)", kid.start_mark.line + 1)
            if id(kid) not in done:
                stack.append((kid, False))
    added = done[id(root)][0] - len(done)
    if added > MAX_YAML_ALIAS_NODES:
        raise _Limit(
            f"its aliases would expand it by {added} nodes (at most {MAX_YAML_ALIAS_NODES}; an alias bomb?)"
        )


def parse_yaml(text: str, where: str, what: str) -> Any:
    """The YAML document in ``text``; a syntax error or a document past the limits names ``where``
    and the line."""
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 (a SafeLoader)
    except _Limit as exc:
        line = f":{exc.line}" if exc.line else ""
        raise InputError(f"{where}{line}: {exc.problem} in {what}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f":{mark.line + 1}" if mark is not None else ""
        problem = " ".join(str(getattr(exc, "problem", None) or exc).split())
        raise InputError(f"{where}{line}: invalid YAML in {what} ({problem})") from None
    except RecursionError:
        raise InputError(f"{where}: YAML nested deeper than {MAX_DEPTH} levels in {what}") from None
    except (ValueError, TypeError, OverflowError) as exc:  # pathological documents
        raise InputError(f"{where}: unreadable YAML in {what} ({type(exc).__name__})") from None


def read_yaml(path: Path, what: str, limit: int = MAX_TEXT_BYTES) -> Any:
    """The YAML document at ``path``: a bounded UTF-8 text, parsed within the limits, every number
    finite."""
    path = Path(path)
    doc = parse_yaml(read_text(path, what, limit=limit), str(path), what)
    check_finite_tree(doc, str(path))
    return doc


# --- JSON ------------------------------------------------------------------------------------------


def _json_int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise _Limit(f"an integer of {digits} digits (at most {MAX_INT_DIGITS})")
    return int(text)


def _json_constant(name: str) -> float:
    return float(name)  # NaN, Infinity, -Infinity: refused by name after the parse


def _depth(doc: Any) -> int:
    deepest = 0
    stack: list[tuple[Any, int]] = [(doc, 1)]
    while stack:
        value, level = stack.pop()
        if isinstance(value, dict | list):
            deepest = max(deepest, level)
            if level > MAX_DEPTH:
                return level
            children = value.values() if isinstance(value, dict) else value
            stack.extend((v, level + 1) for v in children if isinstance(v, dict | list))
    return deepest


def _json_object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object whose keys are each given once (the later one would silently win)."""
    doc: dict[str, Any] = {}
    for key, value in pairs:
        if key in doc:
            raise _Limit(f"duplicate key {key!r} (the later one would silently win)")
        doc[key] = value
    return doc


def parse_json(text: str | bytes, where: str, line: int | None = None, finite: bool = True) -> Any:
    """The JSON document in ``text`` within the limits (depth, integer digits, each key of an object
    once) and, with ``finite``,
    every number finite (``NaN``, ``Infinity``, ``1e999`` refused naming their path); an error names
    ``where`` and the line (``line``: the text is that line of the file)."""
    at = where if line is None else f"{where}:{line}"
    try:
        doc = json.loads(
            text, parse_int=_json_int, parse_constant=_json_constant, object_pairs_hook=_json_object
        )
    except _Limit as exc:
        raise InputError(f"{at}: {exc.problem}") from None
    except RecursionError:
        raise InputError(f"{at}: JSON nested deeper than {MAX_DEPTH} levels") from None
    except json.JSONDecodeError as exc:
        if line is None:
            at = f"{where}:{exc.lineno}"
        raise InputError(f"{at}: not valid JSON: {exc.msg} (column {exc.colno})") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"{at}: not valid JSON ({type(exc).__name__})") from None
    if _depth(doc) > MAX_DEPTH:
        raise InputError(f"{at}: JSON nested deeper than {MAX_DEPTH} levels")
    if finite:
        check_finite_tree(doc, at)
    return doc


def read_json(path: Path, what: str = "a JSON file", limit: int = MAX_TEXT_BYTES) -> Any:
    """The JSON document at ``path``: a bounded UTF-8 text, parsed within the limits, every number
    finite."""
    path = Path(path)
    return parse_json(read_text(path, what, limit=limit), str(path))


def file_sha256(path: Path) -> str:
    """The hex sha256 of a file's bytes, read in blocks of 1 MiB."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()
