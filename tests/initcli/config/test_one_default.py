"""One default per setting, written once: a setting's default lives in its record in
:mod:`initcli.config` only. A collaborator built from the config takes the setting at construction;
none carries a default of its own for it, and none is patched with it after construction (as
``self.escapes.to_long_walls = x.long_walls`` once patched a ``False`` the escapes held while the
config said true)."""

from __future__ import annotations

import ast
import dataclasses
from collections.abc import Iterator
from pathlib import Path

import pytest

from bimkit.settings import settings_of
from initcli.config import SessionConfig

ROOT = Path(__file__).resolve().parents[3] / "initcli"
CONFIG = ROOT / "config"  # where the defaults are written


def _tree(record: type, names: set[str], records: set[str]) -> tuple[set[str], set[str]]:
    """The setting names and the record (section) type names under ``record``."""
    records.add(record.__name__)
    for f, _, tp in settings_of(record):
        if dataclasses.is_dataclass(tp):
            _tree(tp, names, records)  # type: ignore[arg-type]
        else:
            names.add(f.name)
    return names, records


SETTINGS, RECORDS = _tree(SessionConfig, set(), set())
CONFIG_NAMES = {"config", "cfg", "settings"}  # names that hold the session config by convention


def _literal(node: ast.expr | None) -> bool:
    if isinstance(node, ast.UnaryOp):
        node = node.operand
    return isinstance(node, ast.Constant) and node.value is not None


def _root(node: ast.expr) -> ast.expr:
    while isinstance(node, ast.Attribute):
        node = node.value
    return node


def _annotated_record(arg: ast.arg) -> bool:
    """Is ``arg`` annotated with a settings record of the session config (``SessionConfig``,
    ``ExplorationSection``, ``LoopSettings``, ...)?"""
    if arg.annotation is None:
        return False
    return any(isinstance(n, ast.Name) and n.id in RECORDS for n in ast.walk(arg.annotation)) or (
        isinstance(arg.annotation, ast.Constant) and any(r in str(arg.annotation.value) for r in RECORDS)
    )


class _Function:
    """The names in one function that hold the config or a section of it (its parameters so
    annotated or so named, and locals read from them)."""

    def __init__(self, fn: ast.FunctionDef) -> None:
        args = fn.args.posonlyargs + fn.args.args + fn.args.kwonlyargs
        self.holders = {a.arg for a in args if _annotated_record(a) or a.arg in CONFIG_NAMES}
        for node in ast.walk(fn):  # aliases: x = config.exploration; cmap, m = ..., config.matching
            if isinstance(node, ast.Assign):
                for target in node.targets:
                    pairs = (
                        zip(target.elts, node.value.elts, strict=False)
                        if isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple)
                        else [(target, node.value)]
                    )
                    for t, v in pairs:
                        if isinstance(t, ast.Name) and self.reads_config(v):
                            self.holders.add(t.id)

    def reads_config(self, node: ast.expr) -> bool:
        """Is ``node`` a read of the config, a section or a setting (``config.exploration.long_walls``,
        ``x.long_walls``, ``self.config.limits``)?"""
        if not isinstance(node, ast.Attribute | ast.Name):
            return False
        root = _root(node)
        if isinstance(root, ast.Name) and root.id in self.holders:
            return True
        chain = node
        while isinstance(chain, ast.Attribute):
            if isinstance(chain.value, ast.Name) and chain.value.id == "self" and chain.attr in CONFIG_NAMES:
                return True
            chain = chain.value
        return False


def _functions(tree: ast.AST) -> Iterator[ast.FunctionDef]:
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef):
            yield node


def _targets(node: ast.Assign | ast.AnnAssign | ast.AugAssign) -> Iterator[tuple[ast.expr, ast.expr | None]]:
    """(target, value) pairs of an assignment, tuples unpacked pairwise."""
    targets = node.targets if isinstance(node, ast.Assign) else [node.target]
    for target in targets:
        if isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple):
            yield from zip(target.elts, node.value.elts, strict=False)
        else:
            yield target, node.value


def patched_settings(source: str) -> list[str]:
    """Assignments of a setting to an attribute of another object, one already constructed
    (``self.escapes.to_long_walls = x.long_walls``, ``escapes.to_long_walls = config...``): the
    collaborator should have taken it at construction."""
    found = []
    for fn in _functions(ast.parse(source)):
        scope = _Function(fn)
        for node in ast.walk(fn):
            if not isinstance(node, ast.Assign | ast.AnnAssign | ast.AugAssign):
                continue
            for target, value in _targets(node):
                if not isinstance(target, ast.Attribute) or value is None:
                    continue
                owner = target.value
                if isinstance(owner, ast.Name) and owner.id in {"self", "cls"} | scope.holders:
                    continue  # its own attribute, or a config record built here
                if scope.reads_config(value):
                    found.append(f"line {node.lineno}: {ast.unparse(target)} = {ast.unparse(value)}")
    return found


def _switch_named_as_setting(name: str, value: ast.expr | None) -> bool:
    """A switch (True/False) named after a setting, or ending in its name: ``to_long_walls = False``
    (counters such as ``self.hypotheses = 0`` start at a literal of their own)."""
    switch = isinstance(value, ast.Constant) and isinstance(value.value, bool)
    return switch and any(name == s or name.endswith("_" + s) for s in SETTINGS)


def second_defaults(source: str) -> list[str]:
    """Defaults of its own in the constructor of a collaborator built from a settings record: a
    parameter named after a setting with a literal default, or a switch named after one
    (``long_walls``, ``to_long_walls``) set to True or False."""
    found = []
    for fn in _functions(ast.parse(source)):
        args = fn.args.posonlyargs + fn.args.args + fn.args.kwonlyargs
        if fn.name != "__init__" or not any(_annotated_record(a) for a in args):
            continue
        positional = fn.args.posonlyargs + fn.args.args
        defaults = list(
            zip(positional[len(positional) - len(fn.args.defaults) :], fn.args.defaults, strict=True)
        )
        defaults += [
            (a, d) for a, d in zip(fn.args.kwonlyargs, fn.args.kw_defaults, strict=True) if d is not None
        ]
        for arg, default in defaults:
            if arg.arg in SETTINGS and _literal(default):
                found.append(f"line {fn.lineno}: parameter {arg.arg} = {ast.unparse(default)}")
        for node in ast.walk(fn):
            if not isinstance(node, ast.Assign | ast.AnnAssign):
                continue
            for target, value in _targets(node):
                own = isinstance(target, ast.Attribute) and isinstance(target.value, ast.Name)
                if own and target.value.id == "self" and _switch_named_as_setting(target.attr, value):
                    found.append(f"line {node.lineno}: {ast.unparse(target)} = {ast.unparse(value)}")
    return found


def _modules() -> list[Path]:
    return sorted(p for p in ROOT.rglob("*.py") if CONFIG not in p.parents)


def test_the_setting_names_are_read_from_the_config() -> None:
    assert {"long_walls", "wall_side", "max_distance", "tries"} <= SETTINGS
    assert {"SessionConfig", "ExplorationSection", "LapSettings"} <= RECORDS


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(ROOT.parent)))
def test_no_setting_is_patched_after_construction_or_defaulted_twice(path: Path) -> None:
    source = path.read_text(encoding="utf-8")
    found = patched_settings(source) + second_defaults(source)
    assert not found, f"{path.relative_to(ROOT.parent)}: a setting's default in two places:\n" + "\n".join(
        found
    )


OLD_RUNNER = """
class Session:
    def __init__(self, config: SessionConfig, site, result):
        x = config.exploration
        self.escapes = Escapes(x.loops, x.shuttles, x.frontier, result, x.laps)
        self.escapes.to_long_walls = x.long_walls
"""

OLD_ESCAPES = """
class Escapes:
    def __init__(self, loops: LoopSettings, laps: LapSettings | None = None, long_walls: bool = False):
        self.settings = loops
        self.to_long_walls = False
"""


def test_the_scan_finds_the_old_pattern() -> None:
    """The pattern this test exists for: the runner patching the escapes after construction, and
    the escapes' own default that disagreed with exploration.long_walls (true)."""
    assert patched_settings(OLD_RUNNER) == ["line 6: self.escapes.to_long_walls = x.long_walls"]
    assert second_defaults(OLD_ESCAPES) == [
        "line 3: parameter long_walls = False",
        "line 5: self.to_long_walls = False",
    ]
    assert patched_settings(
        "def f(config: SessionConfig, e):\n    e.to_long_walls = config.exploration.long_walls\n"
    )
