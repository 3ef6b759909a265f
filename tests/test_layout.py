"""The house reads the way data flows: no import circle (imports inside functions count), no package
that imports a package importing it back, modules short enough to read in one sitting, ``initcli/core``
in subpackages by concern, the settings one package.

The import graph is read from the source (``ast``), not by importing: a circle hidden by a local
import is one all the same.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.helpers import ROOT

PACKAGES = ("bimkit", "bimtools", "initcli")
MAX_LINES = 600  # no module longer
RUNNER_MAX_LINES = 450  # the session's state machine, the module changed most often


def _modules(root: Path, packages: tuple[str, ...]) -> dict[str, Path]:
    found = {}
    for package in packages:
        for path in (root / package).rglob("*.py"):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join(parts)] = path
    return found


def _owner(name: str, modules: dict[str, Path]) -> str | None:
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def import_graph(root: Path = ROOT, packages: tuple[str, ...] = PACKAGES) -> dict[str, set[str]]:
    """Module -> the project modules it imports, anywhere in its body."""
    modules = _modules(root, packages)
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        targets: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package[: len(package) - node.level + 1] + ([base] if base else []))
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    targets.add(_owner(full if full in modules else base, modules) or "")
            elif isinstance(node, ast.Import):
                targets.update(_owner(alias.name, modules) or "" for alias in node.names)
        graph[name] = {t for t in targets if t and t != name}
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def package_of(module: str) -> str:
    """The room a module stands in: ``initcli.core.lidar``, ``initcli.match``, ``bimtools.site``."""
    parts = module.split(".")
    depth = 3 if parts[:2] == ["initcli", "core"] else 2
    return ".".join(parts[:depth])


def test_no_import_circle_between_modules() -> None:
    assert circles(import_graph()) == []


def test_no_import_circle_between_packages() -> None:
    packages: dict[str, set[str]] = {}
    for module, targets in import_graph().items():
        packages.setdefault(package_of(module), set()).update(
            package_of(t) for t in targets if package_of(t) != package_of(module)
        )
    assert circles(packages) == []


def test_the_circle_finder_finds_a_circle() -> None:
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_a_local_import_counts(tmp_path: Path) -> None:
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg/__init__.py").write_text("")
    (tmp_path / "pkg/a.py").write_text("from pkg.b import x\n")
    (tmp_path / "pkg/b.py").write_text("x = 1\n\n\ndef f():\n    from . import a\n")
    graph = import_graph(tmp_path, ("pkg",))
    assert graph["pkg.b"] == {"pkg.a"}
    assert circles(graph) == [["pkg.a", "pkg.b"]]


@pytest.mark.parametrize("package", PACKAGES)
def test_no_module_over_the_limit(package: str) -> None:
    long = {
        str(p.relative_to(ROOT)): n
        for p in (ROOT / package).rglob("*.py")
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert long == {}


def test_the_runner_stays_short() -> None:
    lines = (ROOT / "initcli/session/runner.py").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= RUNNER_MAX_LINES


def test_core_is_subpackages_by_concern() -> None:
    core = ROOT / "initcli/core"
    assert sorted(p.name for p in core.glob("*.py")) == ["__init__.py"]
    assert {p.name for p in core.iterdir() if (p / "__init__.py").is_file()} >= {
        "geometry",
        "features",
        "hypotheses",
        "lidar",
        "verify",
        "filters",
        "navigation",
    }


def test_core_imports_no_file_format_or_console_library() -> None:
    banned = ("typer", "rich", "initcli.io", "initcli.ros", "initcli.cli", "bimtools.site.load", "yaml")
    offenders = []
    for path in (ROOT / "initcli/core").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = (
                [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else []
            )
            offenders += [f"{path.relative_to(ROOT)}: {n}" for n in names if n.startswith(banned)]
    assert offenders == []


def test_settings_are_one_package() -> None:
    assert not list((ROOT / "initcli").glob("settings*.py"))
    assert not (ROOT / "initcli/config.py").exists()
    assert (ROOT / "initcli/config/__init__.py").is_file()
