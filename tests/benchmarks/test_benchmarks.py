"""The benchmarks, read not run: ``make bench`` and ``make bench-quick`` (CI) name every
``benchmarks/bench_*.py``, each script has the shared ``--quick`` mode, and no benchmark file
reaches into ``tests/`` or changes ``sys.path`` (``tests/bimtools`` would shadow the package)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCHMARKS = ROOT / "benchmarks"
SCRIPTS = sorted(BENCHMARKS.glob("bench_*.py"))
MAKEFILE = (ROOT / "Makefile").read_text()


def _recipe(target: str) -> str:
    match = re.search(rf"^{re.escape(target)}:.*\n((?:\t.*\n)+)", MAKEFILE, re.MULTILINE)
    assert match, f"the Makefile has no {target} target"
    return match.group(1)


def _imports(tree: ast.AST) -> dict[str, set[str]]:
    """Top-level module -> the names imported from it (empty for a plain ``import``)."""
    out: dict[str, set[str]] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                out.setdefault(alias.name.split(".")[0], set())
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.setdefault(node.module.split(".")[0], set()).update(a.name for a in node.names)
    return out


def test_the_makefile_runs_every_benchmark_whole_and_quick() -> None:
    listed = re.search(r"^BENCHMARKS := (.*)$", MAKEFILE, re.MULTILINE)
    assert listed, "the Makefile has no BENCHMARKS list"
    assert sorted(listed.group(1).split()) == [p.stem.removeprefix("bench_") for p in SCRIPTS]
    for target, flag in (("bench", ""), ("bench-quick", " --quick")):
        recipe = _recipe(target)
        assert "for b in $(BENCHMARKS)" in recipe
        assert f"benchmarks/bench_$$b.py{flag};" in recipe
    assert "make bench-quick" in (ROOT / ".ci" / "run").read_text()


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_a_benchmark_parses_its_arguments_with_the_quick_mode(script: Path) -> None:
    tree = ast.parse(script.read_text(), str(script))
    assert "parse_args" in _imports(tree).get("_common", set()), "no --quick: not _common.parse_args"
    calls = [n.func for n in ast.walk(tree) if isinstance(n, ast.Call)]
    assert any(isinstance(f, ast.Name) and f.id == "parse_args" for f in calls)


@pytest.mark.parametrize("path", sorted(BENCHMARKS.glob("*.py")), ids=lambda p: p.name)
def test_no_benchmark_imports_tests_or_changes_sys_path(path: Path) -> None:
    tree = ast.parse(path.read_text(), str(path))
    modules = _imports(tree)
    assert "tests" not in modules and not any(m.startswith("test_") for m in modules)
    assert "path" not in modules.get("sys", set())
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr == "path" and isinstance(node.value, ast.Name):
            assert node.value.id != "sys", f"{path.name}:{node.lineno} uses sys.path"
