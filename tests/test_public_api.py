"""Every public module of bimkit, bimtools and initcli says what it exports: ``__all__``, each of its
names defined at import time, none twice.

A public module is one whose name and package names do not start with an underscore and that binds a
public name at its top level (a package ``__init__`` holding only its docstring exports nothing).
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

from tests.helpers import ROOT

PACKAGES = ("bimkit", "bimtools", "initcli")

# Modules another helper is rewriting for issue 28, without ``__all__`` until that lands. Shrink this
# list as they gain one (the test below fails for an entry that no longer needs to be here).
WITHOUT_ALL: set[str] = set()

# Optional extras a module may need at import (the test of such a module is skipped without it).
OPTIONAL = {"torch", "ray", "roslibpy", "onnx"}


def _public_modules() -> list[str]:
    found = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            rel = path.relative_to(ROOT)
            if any(p.startswith("_") and p not in ("__init__.py", "__main__.py") for p in rel.parts):
                continue
            if _public_names(path):
                found.append(rel.as_posix())
    return found


def _bound(target: ast.expr) -> list[str]:
    if isinstance(target, ast.Name):
        return [target.id]
    if isinstance(target, ast.Tuple | ast.List):
        return [n for e in target.elts for n in _bound(e)]
    return []


def _top_level(tree: ast.Module) -> list[str]:
    names: list[str] = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.append(node.name)
        elif isinstance(node, ast.Assign):
            names += [n for t in node.targets for n in _bound(t)]
        elif isinstance(node, ast.AnnAssign):
            names += _bound(node.target)
    return names


def _public_names(path: Path) -> list[str]:
    return [n for n in _top_level(ast.parse(path.read_text(encoding="utf-8"))) if not n.startswith("_")]


def _module_name(rel: str) -> str:
    parts = rel.removesuffix(".py").split("/")
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = _public_modules()


def test_the_modules_are_found():
    assert {"bimkit/checks.py", "bimtools/site/load.py", "initcli/match/pipeline.py"} <= set(MODULES)
    assert "initcli/core/__init__.py" not in MODULES  # a package docstring only


@pytest.mark.parametrize("rel", MODULES)
def test_public_module_defines_all(rel: str):
    has_all = "__all__" in _top_level(ast.parse((ROOT / rel).read_text(encoding="utf-8")))
    if rel in WITHOUT_ALL:
        assert not has_all, f"{rel} defines __all__ now: remove it from WITHOUT_ALL"
        return
    assert has_all, f"{rel}: a public module without __all__"
    try:
        module = importlib.import_module(_module_name(rel))
    except ModuleNotFoundError as exc:
        if exc.name in OPTIONAL:
            pytest.skip(f"{rel} needs {exc.name}")
        raise
    exported = module.__all__
    assert isinstance(exported, list) and all(isinstance(n, str) for n in exported)
    assert len(set(exported)) == len(exported), f"{rel}: a name twice in __all__"
    missing = [n for n in exported if not hasattr(module, n)]
    assert not missing, f"{rel}: __all__ names {missing}, which the module does not define"


def test_allow_list_names_real_modules():
    assert WITHOUT_ALL <= set(MODULES), sorted(WITHOUT_ALL - set(MODULES))
