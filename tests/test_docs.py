"""The README and the docs site: length, command table, the minimal site.yaml, links, generators.

``make docs`` builds the site in strict mode (broken links, anchors and cross-references fail it);
these tests check the same things without MkDocs, plus what MkDocs cannot know: that the commands
the README lists exist, that its site.yaml is valid, and that the generators see new packages.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
import unicodedata
from pathlib import Path

import jsonschema
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
SCHEMA = ROOT / "bimkit/schemas/site_config.schema.json"
MINIMAL_SITE = DOCS / "examples/site.yaml"

_spec = importlib.util.spec_from_file_location("docgen", DOCS / "gen/docgen.py")
assert _spec and _spec.loader
docgen = importlib.util.module_from_spec(_spec)
sys.modules["docgen"] = docgen
_spec.loader.exec_module(docgen)

LINK = re.compile(r"(?<!\])\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
AUTOREF = re.compile(r"\]\[([A-Za-z_][\w.]*)\]|\[`?([A-Za-z_][\w.]*)`?\]\[\]")
SNIPPET = re.compile(r'^\s*--8<--\s+"([^"]+)"', re.M)


def _strip_fences(text: str) -> str:
    """Markdown without its fenced code blocks (``` ... ```, indented or not)."""
    kept, fence = [], ""
    for line in text.splitlines():
        stripped = line.strip()
        if fence:
            if stripped == fence:
                fence = ""
            continue
        if stripped.startswith("```"):
            fence = "```"
            continue
        kept.append(line)
    return "\n".join(kept)


def _strip_code(text: str) -> str:
    """Markdown without fenced blocks and inline code (links there are not links)."""
    return re.sub(r"`[^`\n]*`", "", _strip_fences(text))


def _slug(heading: str) -> str:
    """Python-Markdown's toc slugify (the ids MkDocs gives headings; GitHub's are the same here)."""
    text = re.sub(r"<[^>]+>", "", heading).replace("`", "")
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def _anchors(text: str) -> set[str]:
    ids = set(re.findall(r'\bid="([^"]+)"', text)) | set(re.findall(r"\{\s*#([\w.-]+)\s*\}", text))
    for line in _strip_fences(text).splitlines():
        match = re.match(r"^#{1,6}\s+(.*?)\s*(\{[^}]*\})?\s*$", line)
        if match:
            ids.add(_slug(match.group(1)))
    return ids


def _site_pages() -> dict[str, str | None]:
    """Every file of the docs build: path -> Markdown text (None for images and other files)."""
    pages: dict[str, str | None] = {}
    for path in DOCS.rglob("*"):
        rel = path.relative_to(DOCS).as_posix()
        if path.is_file() and not rel.startswith("gen/"):
            pages[rel] = path.read_text(encoding="utf-8") if path.suffix == ".md" else None
    for page in docgen.generated_pages(ROOT):  # figures are drawn lazily: listing them is cheap
        pages[page.path] = (
            page.content if page.path.endswith(".md") and isinstance(page.content, str) else None
        )
    return pages


def _broken_links(text: str, where: str, resolve) -> list[str]:
    problems = []
    for target in LINK.findall(_strip_code(text)):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):
            continue  # https:, mailto:
        path, _, anchor = target.partition("#")
        found = resolve(path)
        if found is False:
            problems.append(f"{where}: {target}: no such file")
        elif anchor and isinstance(found, str) and anchor not in _anchors(found):
            problems.append(f"{where}: {target}: no anchor #{anchor}")
    return problems


def _help(*args: str) -> str:
    code = "import sys; from initcli.cli.main import main; sys.argv[0] = 'bim-init'; main()"
    if args and args[0] == "bim-extract":
        code = "import sys; from bimtools.cli import main; sys.argv[0] = 'bim-extract'; main()"
        args = args[1:]
    env = dict(os.environ, COLUMNS="200", NO_COLOR="1", TERM="dumb")
    done = subprocess.run(
        [sys.executable, "-c", code, *args, "--help"],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def _listed_commands(help_text: str) -> set[str]:
    return {m.group(1) for m in re.finditer(r"^[│|]?\s{1,4}([a-z][a-z0-9-]*)\s{2,}\S", help_text, re.M)}


# --------------------------------------------------------------------------------------------------
# README
# --------------------------------------------------------------------------------------------------


def test_readme_is_at_most_300_lines():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 300, f"README.md has {len(lines)} lines; move text to docs/"


def _readme_commands() -> list[list[str]]:
    text = README.read_text(encoding="utf-8")
    section = text.split("## Commands", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\|\s*`([^`]+)`\s*\|", section, re.M)
    return [row.split() for row in rows]


def test_readme_command_table_lists_the_commands_the_cli_has():
    commands = _readme_commands()
    assert ["bim-extract"] in commands and ["bim-init", "run"] in commands
    top = _listed_commands(_help())
    assert {"match", "run", "eval"} <= top, "the help parser no longer reads bim-init --help"
    for words in commands:
        assert words[0] in ("bim-init", "bim-extract"), words
        if words[0] == "bim-extract":
            assert "MODEL.ifc" in _help("bim-extract")
            continue
        assert words[1] in top, f"`{' '.join(words)}`: bim-init --help does not list {words[1]!r}"
        if len(words) > 2:
            sub = _listed_commands(_help(words[1]))
            assert words[2] in sub, f"`{' '.join(words)}`: bim-init {words[1]} --help does not list it"


def test_every_cli_command_is_in_the_readme_table():
    listed = {words[1] for words in _readme_commands() if words[0] == "bim-init"}
    assert _listed_commands(_help()) <= listed


def test_readme_site_yaml_is_the_docs_example_and_valid():
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"^( *)```yaml\n(.*?)^\1```", text, re.M | re.S)
    assert blocks, "the README's five steps have no yaml example"
    indent, body = blocks[0]
    example = "\n".join(line[len(indent) :] for line in body.splitlines()) + "\n"
    assert example == MINIMAL_SITE.read_text(encoding="utf-8"), (
        "README's site.yaml differs from docs/examples"
    )
    doc = yaml.safe_load(example)
    jsonschema.validate(doc, json.loads(SCHEMA.read_text(encoding="utf-8")))
    assert doc["robot"]["driver"] == "rosbridge" and doc["site"]["path"]


@pytest.mark.parametrize("name", ["README.md", "CHANGELOG.md", "initcli/detector/README.md"])
def test_repository_markdown_relative_links_resolve(name):
    """Read on GitHub: links relative to the file, into the source tree and docs/."""
    source = ROOT / name
    text = source.read_text(encoding="utf-8")

    def resolve(path: str) -> str | bool | None:
        if not path:
            return text
        target = source.parent / path
        if not target.exists():
            return False
        return target.read_text(encoding="utf-8") if target.suffix == ".md" else None

    assert LINK.findall(_strip_code(text)), f"{name} has no links to check"
    assert _broken_links(text, name, resolve) == []


def test_readme_links_into_the_docs():
    links = LINK.findall(_strip_code(README.read_text(encoding="utf-8")))
    assert {"docs/own-building.md", "docs/site-yaml.md", "docs/ros.md", "CHANGELOG.md"} <= set(links)


# --------------------------------------------------------------------------------------------------
# docs
# --------------------------------------------------------------------------------------------------


def test_docs_relative_links_and_snippets_resolve():
    pages = _site_pages()
    problems = []
    for rel, text in pages.items():
        if text is None:
            continue
        base = Path(rel).parent

        def resolve(path: str, text: str = text, base: Path = base) -> str | bool | None:
            if not path:
                return text
            key = os.path.normpath((base / path).as_posix()).replace(os.sep, "/")
            if key.endswith("/") or key in ("", "."):
                key = f"{key.rstrip('/')}/index.md".lstrip("./")
            return pages[key] if key in pages else False

        problems += _broken_links(text, rel, resolve)
        for snippet in SNIPPET.findall(text):
            if not (ROOT / snippet).is_file():
                problems.append(f"{rel}: snippet {snippet}: no such file")
    assert problems == []


def test_docs_cross_references_name_existing_code():
    modules = set(docgen.package_modules(ROOT))
    problems = []
    for path in DOCS.rglob("*.md"):
        for explicit, empty in AUTOREF.findall(_strip_code(path.read_text(encoding="utf-8"))):
            ident = explicit or empty
            if "." not in ident:
                continue
            parts = ident.split(".")
            prefix = next((i for i in range(len(parts), 0, -1) if ".".join(parts[:i]) in modules), 0)
            if not prefix:
                problems.append(f"{path.name}: [{ident}]: no such module")
                continue
            rest = parts[prefix:]
            if rest:
                source = (ROOT / docgen._module_source(".".join(parts[:prefix]), ROOT)).read_text(
                    encoding="utf-8"
                )
                if not re.search(rf"^\s*(def|class)\s+{rest[0]}\b|^{rest[0]}\s*[:=]", source, re.M):
                    problems.append(f"{path.name}: [{ident}]: {rest[0]} not in the module")
    assert problems == []


def _numeric_settings() -> list[tuple[str, float]]:
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    out = []
    for key, node, is_section in docgen._leaves(schema, ""):
        value = node.get("default")
        if not is_section and isinstance(value, int | float) and not isinstance(value, bool):
            out.append((key, float(value)))
    return out


def test_hand_written_docs_do_not_restate_setting_defaults():
    """A default next to its setting's name drifts when the code changes: link the reference."""
    texts = {p.relative_to(ROOT).as_posix(): p.read_text(encoding="utf-8") for p in DOCS.rglob("*.md")}
    texts["README.md"] = README.read_text(encoding="utf-8")
    problems = []
    for key, value in _numeric_settings():
        leaf = re.escape(key.rsplit(".", 1)[-1])
        number = f"{value:g}".replace(".", r"\.")
        pattern = re.compile(rf"`(?:[\w.]+\.)?{leaf}`\)?\s*(?:\(|=|:|of|is)?\s*{number}(?![\d.])")
        for where, text in texts.items():
            for found in pattern.finditer(_strip_fences(text)):
                problems.append(f"{where}: {found.group(0)!r} restates {key}'s default")
    assert problems == []


# --------------------------------------------------------------------------------------------------
# generators
# --------------------------------------------------------------------------------------------------


def _tree(root: Path, files: list[str], include: list[str]) -> None:
    (root / "pyproject.toml").write_text(
        "[tool.setuptools.packages.find]\ninclude = [" + ", ".join(f'"{i}"' for i in include) + "]\n"
    )
    for name in files:
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text('"""A module."""\n')


def test_api_pages_follow_the_packages_pyproject_includes(tmp_path):
    _tree(
        tmp_path,
        [
            "bimkit/__init__.py",
            "bimkit/geometry.py",
            "initcli/__init__.py",
            "initcli/detector/__init__.py",
            "initcli/detector/synth/__init__.py",
            "initcli/detector/synth/render.py",
            "initcli/detector/training/__init__.py",
            "initcli/detector/_private.py",
            "initcli/notapackage/module.py",
            "tests/__init__.py",
            "tests/test_x.py",
        ],
        ["bimkit*", "initcli*"],
    )
    assert docgen.package_modules(tmp_path) == [
        "bimkit",
        "bimkit.geometry",
        "initcli",
        "initcli.detector",
        "initcli.detector.synth",
        "initcli.detector.synth.render",
        "initcli.detector.training",
    ]
    pages = {p.path: p.content for p in docgen.api_pages(tmp_path)}
    assert pages["reference/api/initcli/detector/synth/render.md"].startswith(
        "::: initcli.detector.synth.render"
    )
    assert "::: initcli.detector.synth" in pages["reference/api/initcli/detector/synth/index.md"]
    nav = pages["reference/api/SUMMARY.md"]
    assert "        * [synth](initcli/detector/synth/index.md)" in nav
    assert "tests" not in nav and "_private" not in nav


def test_api_pages_cover_this_repository():
    modules = docgen.package_modules(ROOT)
    assert "initcli.core.hypotheses.matching" in modules and "bimtools.extract.features" in modules
    assert not any(m.startswith("tests") for m in modules)


def test_settings_page_has_every_schema_key_with_its_default():
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    page = docgen.settings_table(schema)
    for key, node, is_section in docgen._leaves(schema, ""):
        if "." not in key:
            assert f"## `{key}`" in page, key  # a top-level section is a heading
            continue
        assert f'<a id="{key}"></a>' in page, key
        if not is_section and "default" in node:
            row = next(line for line in page.splitlines() if f'<a id="{key}"></a>' in line)
            assert docgen._default_of(node) in row, key
    row = next(line for line in page.splitlines() if 'id="robot.radius"' in line)
    assert "| m |" in row and "(0, 2]" in row


@pytest.mark.parametrize(
    ("description", "unit", "text"),
    [
        ("m: the robot's footprint radius, (0, 5]", "m", "the robot's footprint radius, (0, 5]"),
        ("m/s: top linear speed", "m/s", "top linear speed"),
        ("m, sigma: doors built off their place", "m, sigma", "doors built off their place"),
        ("m kept to the followed wall", "m", "m kept to the followed wall"),
        (
            "rosbridge: false listens only while a person drives",
            "",
            "rosbridge: false listens only while a person drives",
        ),
    ],
)
def test_split_unit(description, unit, text):
    assert docgen.split_unit(description) == (unit, text)


def test_results_table_counts_the_records():
    records = [
        {"site": "a", "method": "bim", "success": True, "confident_wrong": False, "distance_m": 10.0,
         "error_translation_m": 0.1, "error_rotation_deg": 1.0, "features": 4},
        {"site": "a", "method": "bim", "success": True, "confident_wrong": True, "distance_m": 20.0,
         "error_translation_m": 3.0, "error_rotation_deg": 40.0, "features": 6},
        {"site": "a", "method": "bim", "success": False, "confident_wrong": False, "distance_m": 150.0,
         "error_translation_m": None, "error_rotation_deg": None, "features": 2},
    ]  # fmt: skip
    row = docgen.results_table(records).splitlines()[2]
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[:5] == ["a", "`bim`", "3", "2/3 (67 %)", "1"]
    assert cells[5] == "15.0 / 15.0"  # over the successes only
    assert cells[6] == "1.550 / 1.550 / 3.000"


def test_results_pages_come_from_committed_records_with_their_provenance():
    pages = {p.path: p for p in docgen.results_pages(ROOT)}
    files = [folder / "results.jsonl" for folder in docgen.record_folders(ROOT)]
    assert files, "no results.jsonl under benchmarks/results/"
    assert not any(path.startswith("results/archive") for path in pages), "archived records got pages"
    for path in files:
        name = path.parent.relative_to(ROOT / "benchmarks/results").as_posix().replace("/", "-")
        page = pages[f"results/{name}.md"].content
        assert f"{len(docgen.read_records(path))} trials" in page
        if (path.parent / "provenance.json").is_file():
            info = json.loads((path.parent / "provenance.json").read_text(encoding="utf-8"))
            assert info["command"] in page and info["commit"] in page
        assert f"results/{name}-success.png" in pages


def _record(site: str, success: bool, distance: float, wrong: bool = False, **extra) -> str:
    return json.dumps(
        {"site": site, "method": "bim+pf", "success": success, "confident_wrong": wrong,
         "distance_m": distance, **extra}
    )  # fmt: skip


def test_records_tables_are_read_from_the_records_and_the_archive_is_left_out(tmp_path):
    base = tmp_path / "benchmarks/results"
    (base / "old").mkdir(parents=True)
    (base / "old/results.jsonl").write_text(
        "\n".join([_record("a", True, 10.0), _record("a", False, 150.0, True), _record("b", True, 4.0),
                   _record("b", True, 99.0, sweep_key="k", sweep_value="1")]) + "\n"
    )  # fmt: skip
    (base / "old/provenance.json").write_text('{"command": "bim-init eval", "commit": "abcdef0123"}')
    (base / "archive/older").mkdir(parents=True)
    (base / "archive/older/results.jsonl").write_text(_record("a", True, 1.0) + "\n")
    assert [f.name for f in docgen.record_folders(tmp_path)] == ["old"]
    table = docgen.records_table(["old"], tmp_path).splitlines()
    head = [c.strip() for c in table[0].strip("|").split("|")]
    assert head[-2:] == ["a: success, mean distance", "b: success, mean distance"]
    cells = [c.strip() for c in table[2].strip("|").split("|")]
    assert cells[:6] == ["[old](../results/old.md)", "`abcdef0`", "`bim+pf`", "3", "2/3 (67 %)", "1"]
    assert cells[6:] == ["1/2, 10.0 m", "1/1, 4.0 m"]  # sweeps left out; distances of successes
    (tmp_path / "docs/topic").mkdir(parents=True)
    (tmp_path / "docs/topic/page.md").write_text("# Topic\n\n<!-- records: old -->\n\nold is cited.\n")
    (tmp_path / "docs/top.md").write_text("# Top\n\n<!-- records: old -->\n")
    (tmp_path / "docs/plain.md").write_text("# Plain\n")
    pages = {p.path: p for p in docgen.expanded_pages(tmp_path)}
    assert sorted(pages) == ["top.md", "topic/page.md"] and pages["top.md"].source == "docs/top.md"
    assert "| [old](../results/old.md) |" in pages["topic/page.md"].content  # links from the page
    assert "| [old](results/old.md) |" in pages["top.md"].content
    assert "<!-- records" not in pages["topic/page.md"].content
    assert docgen.cited_records(tmp_path) == {"old": ["docs/top.md", "docs/topic/page.md"]}


def test_every_record_the_results_folder_keeps_is_cited_and_listed_in_its_readme():
    """benchmarks/results/ holds only records the docs cite (the rest is in its archive/), and its
    README lists each; every record a page's table names exists there."""
    cited = docgen.cited_records(ROOT)
    readme = (ROOT / "benchmarks/results/README.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"^\| \[`([\w/-]+)`\]", readme, re.M))
    assert sorted(name for name, where in cited.items() if not where) == [], "cited nowhere: archive them"
    assert listed == set(cited), "benchmarks/results/README.md does not list the records kept"
    assert docgen.expanded_pages(ROOT), "no page builds a table from the records"
