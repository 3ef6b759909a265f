"""The generated pages of the docs site, as plain functions (no MkDocs import).

``docs/gen/build.py`` (run by the mkdocs-gen-files plugin during ``make docs``) writes what these
return into the build; ``tests/test_docs.py`` calls the same functions to know which pages exist.
Nothing here is hand-copied: every page is derived at build time from a file in the repository.

* API reference: one page per module of every package that pyproject's
  ``[tool.setuptools.packages.find] include`` selects, found by walking the source tree, so a
  package or module added or moved later appears without editing the docs.
* Settings reference: every key of ``site_config.schema.json`` (and ``eval_config.schema.json``)
  with its type, default, unit, range and description; the file formats of the other schemas.
* Results: tables and figures from every ``results.jsonl`` under ``benchmarks/results/`` (the
  superseded records in ``benchmarks/results/archive/`` are left out).
* Record tables: a hand-written page's line ``<!-- records: NAME ... -->`` becomes a table of
  those record folders (success, confident wrong and mean distance per site), read from their
  ``results.jsonl`` at build time (``expanded_pages``).
* Copies: ``CHANGELOG.md``, the detector's model card and the default categories file.
"""

from __future__ import annotations

import ast
import fnmatch
import io
import json
import math
import re
import statistics
import subprocess
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = [
    "Page",
    "api_pages",
    "cited_records",
    "copied_pages",
    "expanded_pages",
    "generated_pages",
    "package_modules",
    "real_lidar_page",
    "watch_page",
    "real_lidar_table",
    "record_folders",
    "records_table",
    "results_pages",
    "schema_pages",
    "settings_table",
]

ROOT = Path(__file__).resolve().parents[2]
SCHEMA_DIR = Path("bimkit/schemas")
RESULTS_DIR = Path("benchmarks/results")
ARCHIVE = "archive"  # benchmarks/results/archive/: superseded records, no page, cited nowhere
API_DIR = "reference/api"
RESULTS_PAGES = "results"
REAL_LIDAR = RESULTS_DIR / "real_lidar" / "real_lidar.json"  # bench_real_lidar.py --out
WATCH = RESULTS_DIR / "watch" / "watch.json"  # bench_watch.py --out

# A description starting with one of these words (then ":" or ",") names the setting's unit.
UNITS = (
    "m",
    "m/s",
    "rad/s",
    "px",
    "degrees",
    "radians",
    "Hz",
    "s",
    "m^2",
    "rad^2",
    "rad^2/rad",
    "rad^2/m",
    "m^2/m",
    "m^2/rad",
)


@dataclass(frozen=True)
class Page:
    """One file of the build: its path inside the docs tree, its content and its source."""

    path: str
    content: str | bytes | Callable[[], bytes]  # a callable draws a figure only when written
    source: str | None = None  # the repository file it is derived from (the page's edit link)

    def data(self) -> str | bytes:
        """The content, drawing it first when it is a figure."""
        return self.content() if callable(self.content) else self.content


# --------------------------------------------------------------------------------------------------
# API reference
# --------------------------------------------------------------------------------------------------


def package_patterns(root: Path = ROOT) -> list[str]:
    """The ``include`` patterns of pyproject's ``[tool.setuptools.packages.find]``."""
    with open(root / "pyproject.toml", "rb") as handle:
        project = tomllib.load(handle)
    find = project.get("tool", {}).get("setuptools", {}).get("packages", {}).get("find", {})
    return list(find.get("include", []))


def _included(name: str, patterns: list[str]) -> bool:
    return any(fnmatch.fnmatchcase(name, pattern) for pattern in patterns)


def package_modules(root: Path = ROOT) -> list[str]:
    """Dotted names of every package and public module setuptools would ship, sorted.

    A package is a folder with an ``__init__.py`` (as ``setuptools.packages.find`` sees it) whose
    dotted name matches an include pattern; its modules are its ``.py`` files not starting with
    ``_``. Folders without ``__init__.py`` are not packages and are not entered.
    """
    patterns = package_patterns(root)
    names: list[str] = []

    def walk(folder: Path, dotted: str) -> None:
        if not (folder / "__init__.py").is_file():
            return
        if _included(dotted, patterns):
            names.append(dotted)
            for module in sorted(folder.glob("*.py")):
                if not module.name.startswith("_"):
                    names.append(f"{dotted}.{module.stem}")
        for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
            if not sub.name.startswith((".", "_")) and sub.name.isidentifier():
                walk(sub, f"{dotted}.{sub.name}")

    for top in sorted(p for p in root.iterdir() if p.is_dir() and p.name.isidentifier()):
        walk(top, top.name)
    return sorted(names)


def _module_source(dotted: str, root: Path) -> str:
    path = Path(*dotted.split("."))
    return (path / "__init__.py").as_posix() if (root / path).is_dir() else path.with_suffix(".py").as_posix()


def _summary(root: Path, dotted: str) -> str:
    """The first paragraph of a package's docstring, on one line, Sphinx roles as code."""
    text = (root / Path(*dotted.split(".")) / "__init__.py").read_text(encoding="utf-8")
    try:
        doc = ast.get_docstring(ast.parse(text)) or ""
    except SyntaxError:
        return ""
    first = " ".join(doc.split("\n\n", 1)[0].split())
    return re.sub(r":[a-z]+:`~?([^`]+)`", r"`\1`", first).replace("``", "`")


def api_pages(root: Path = ROOT) -> list[Page]:
    """One mkdocstrings page per module, a package's page its ``index.md``, and the nav."""
    modules = package_modules(root)
    packages = {m for m in modules if (root / Path(*m.split("."))).is_dir()}
    pages: list[Page] = []
    nav = ["# API reference", ""]
    for dotted in modules:
        parts = dotted.split(".")
        rel = "/".join(parts) + ("/index.md" if dotted in packages else ".md")
        options = "    options:\n      show_submodules: false\n" if dotted in packages else ""
        pages.append(Page(f"{API_DIR}/{rel}", f"::: {dotted}\n{options}", _module_source(dotted, root)))
        nav.append("    " * (len(parts) - 1) + f"* [{parts[-1]}]({rel})")
    index = [
        "# API reference",
        "",
        "Generated from the docstrings of every module the wheel ships (the packages matching `"
        + "`, `".join(package_patterns(root))
        + "` in pyproject.toml, found by walking the source tree at build time).",
        "",
        "## Package layout",
        "",
        "Each package with the first paragraph of its docstring:",
        "",
        "| package | what it holds | modules |",
        "|---|---|---|",
    ]
    for dotted in sorted(packages):
        count = sum(1 for m in modules if m.rsplit(".", 1)[0] == dotted and m not in packages)
        link = "/".join(dotted.split(".")) + "/index.md"
        index.append(f"| [`{dotted}`]({link}) | {_cell(_summary(root, dotted))} | {count} |")
    pages.append(Page(f"{API_DIR}/index.md", "\n".join(index) + "\n"))
    pages.append(Page(f"{API_DIR}/SUMMARY.md", "* [Overview](index.md)\n" + "\n".join(nav[2:]) + "\n"))
    return pages


# --------------------------------------------------------------------------------------------------
# Settings reference and file formats, from the JSON Schemas
# --------------------------------------------------------------------------------------------------


def _cell(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _type_of(node: dict) -> str:
    if "enum" in node:
        return "one of " + ", ".join(f"`{v}`" for v in node["enum"])
    if "const" in node:
        return f"`{node['const']}`"
    if "oneOf" in node or "anyOf" in node:
        return " or ".join(_type_of(n) for n in node.get("oneOf", node.get("anyOf", [])))
    kind = node.get("type", "")
    if isinstance(kind, list):
        kind = " or ".join(kind)
    if kind == "object" and "additionalProperties" in node and "properties" not in node:
        values = node["additionalProperties"]
        return "mapping" + (f" to {_type_of(values)}" if isinstance(values, dict) and values else "")
    if kind == "array":
        items = node.get("items")
        count = ""
        if "minItems" in node and node.get("minItems") == node.get("maxItems"):
            count = f"{node['minItems']} "
        return f"list of {count}{_type_of(items)}" if isinstance(items, dict) and items else "list"
    if "$ref" in node:
        return f"`{node['$ref'].rsplit('/', 1)[-1]}`"
    return kind or "any"


def _range_of(node: dict) -> str:
    low = node.get("minimum", node.get("exclusiveMinimum"))
    high = node.get("maximum", node.get("exclusiveMaximum"))
    if low is None and high is None:
        return ""
    left = "(" if "exclusiveMinimum" in node or low is None else "["
    right = ")" if "exclusiveMaximum" in node or high is None else "]"
    return f"{left}{'-inf' if low is None else low}, {'inf' if high is None else high}{right}"


def _default_of(node: dict) -> str:
    if "default" not in node:
        return ""
    value = node["default"]
    if isinstance(value, bool):
        return f"`{str(value).lower()}`"
    if value == "":
        return '`""`'
    if isinstance(value, dict | list):
        return f"`{json.dumps(value)}`"
    return f"`{value}`"


def split_unit(description: str) -> tuple[str, str]:
    """``("m", "the robot's footprint radius")`` from ``"m: the robot's footprint radius"``."""
    match = re.match(r"^(\S+?)(?:(, sigma)?[:,]\s+|\s+)(.*)$", description)
    if match and match.group(1) in UNITS:
        unit = match.group(1) + (match.group(2) or "")
        separated = description[len(match.group(1)) + len(match.group(2) or "")] in ":,"
        return unit, match.group(3) if separated else description
    return "", description


def _leaves(node: dict, prefix: str) -> Iterator[tuple[str, dict, bool]]:
    """(dotted key, schema node, is_section) in document order."""
    for key, child in node.get("properties", {}).items():
        dotted = f"{prefix}.{key}" if prefix else key
        items = child.get("items") if child.get("type") == "array" else None
        if "properties" in child:
            yield dotted, child, True
            yield from _leaves(child, dotted)
        elif isinstance(items, dict) and "properties" in items:
            yield dotted, child, True
            yield from _leaves(items, f"{dotted}[]")
        else:
            yield dotted, child, False


def settings_table(schema: dict, anchors: bool = True) -> str:
    """One Markdown table per top-level section: key, type, default, unit, range, description."""
    out: list[str] = []
    header = "| key | type | default | unit | range | description |\n|---|---|---|---|---|---|"
    for section, node in schema.get("properties", {}).items():
        required = section in schema.get("required", [])
        out.append(f"## `{section}`" + (" (required)" if required else "") + "\n")
        if node.get("description") and ("properties" in node or "items" in node):
            out.append(node["description"] + "\n")
        rows = [r for r in _leaves({"properties": {section: node}}, "") if r[0] != section or not r[2]]
        out.append(header)
        for dotted, child, is_section in rows:
            anchor = f'<a id="{dotted}"></a>' if anchors else ""
            if is_section:
                text = child.get("description", "")
                out.append(f"| {anchor}**`{dotted}`** | section | | | | {_cell(text)} |")
                continue
            unit, text = split_unit(child.get("description", ""))
            parent = dotted.rsplit(".", 1)[0]
            if dotted.rsplit(".", 1)[-1] in _required_in(node, parent, section):
                text = "required. " + text
            out.append(
                f"| {anchor}`{dotted}` | {_cell(_type_of(child))} | {_cell(_default_of(child))} | "
                f"{_cell(unit)} | {_cell(_range_of(child))} | {_cell(text)} |"
            )
        out.append("")
    return "\n".join(out)


def _required_in(section_node: dict, parent: str, section: str) -> list[str]:
    """The ``required`` list of the object that holds the keys under ``parent``."""
    if parent.split(".")[0].removesuffix("[]") != section:
        return []
    node = section_node
    for part in parent.split(".")[1:]:
        node = node.get("properties", {}).get(part.removesuffix("[]"), {})
        if part.endswith("[]"):
            node = node.get("items", {})
    if parent.split(".")[0].endswith("[]"):
        node = node.get("items", {})
    return list(node.get("required", []))


SETTINGS_INTRO = """# Settings reference: `site.yaml`

Every key of the session config that `bim-init run`, `bim-init survey --config` and the site
configs named by an `eval.yaml` read, generated at build time from
`bimkit/schemas/site_config.schema.json` (the schema the config is validated against before
anything runs), so this page cannot disagree with the code. Every key is optional except
`site.path`; a key left out takes the default shown. Units: m, degrees (radians only where the
unit column says so), s, px. The same names and units are the options of `bim-init match`
(`--alpha` is `matching.alpha`, and so on) and the `--sweep KEY=...` keys of `bim-init eval`.
How to write one: [Writing a site.yaml](../site-yaml.md).

"""

EVAL_INTRO = """# Settings reference: `eval.yaml`

Every key of the `bim-init eval` config, generated at build time from
`bimkit/schemas/eval_config.schema.json`. How the evaluation runs:
[bim-init eval](../eval.md).

"""


def _schema_formats(root: Path) -> str:
    out = [
        "# File formats",
        "",
        "Every file bim-init reads or writes has a JSON Schema in `bimkit/schemas/` (the source "
        "tree's `schemas/` links there; the wheel ships them). This page is generated from those "
        "files at build time. The session and evaluation configs have pages of their own: "
        "[site.yaml](settings.md), [eval.yaml](eval-config.md).",
        "",
    ]
    for path in sorted((root / SCHEMA_DIR).glob("*.schema.json")):
        if path.name in ("site_config.schema.json", "eval_config.schema.json"):
            continue
        schema = json.loads(path.read_text(encoding="utf-8"))
        out.append(f"## {schema.get('title', path.name)}\n")
        out.append(f"`{SCHEMA_DIR.as_posix()}/{path.name}`\n")
        if schema.get("description"):
            out.append(schema["description"] + "\n")
        parts = [("", schema)] + [(f"$defs.{k}", v) for k, v in schema.get("$defs", {}).items()]
        for label, node in parts:
            rows = [r for r in _leaves(node, "") if not r[2]]
            if not rows:
                continue
            if label:
                out.append(
                    f"`{label}`" + (f": {node['description']}" if node.get("description") else "") + "\n"
                )
            out.append("| field | type | description |\n|---|---|---|")
            for dotted, child, _ in rows:
                out.append(
                    f"| `{dotted}` | {_cell(_type_of(child))} | {_cell(child.get('description', ''))} |"
                )
            out.append("")
    return "\n".join(out)


def schema_pages(root: Path = ROOT) -> list[Page]:
    """The settings reference of site.yaml and eval.yaml, and the file formats."""
    site = json.loads((root / SCHEMA_DIR / "site_config.schema.json").read_text(encoding="utf-8"))
    evals = json.loads((root / SCHEMA_DIR / "eval_config.schema.json").read_text(encoding="utf-8"))
    return [
        Page(
            "reference/settings.md",
            SETTINGS_INTRO + settings_table(site),
            f"{SCHEMA_DIR}/site_config.schema.json",
        ),
        Page(
            "reference/eval-config.md",
            EVAL_INTRO + settings_table(evals),
            f"{SCHEMA_DIR}/eval_config.schema.json",
        ),
        Page("reference/file-formats.md", _schema_formats(root)),
    ]


# --------------------------------------------------------------------------------------------------
# Copies of repository files
# --------------------------------------------------------------------------------------------------

_LINK = re.compile(r"(?<!!)\[([^\]]+)\]\(([^)\s]+)\)")


def _unlink_relative(text: str, docs_prefix: str | None = None) -> str:
    """Relative links of a file copied into the docs point into the source tree: keep their text.

    With ``docs_prefix`` (the way from the file to ``docs/``, as ``"docs/"`` from the repository's
    root), a link into the docs stays a link, to the page as the site has it (the copy lands at
    the site's root)."""

    def repl(match: re.Match[str]) -> str:
        target = match.group(2)
        if re.match(r"^[a-z]+:|^#", target):
            return match.group(0)
        if docs_prefix and target.startswith(docs_prefix) and ".md" in target:
            return f"[{match.group(1)}]({target.removeprefix(docs_prefix)})"
        return match.group(1)

    return _LINK.sub(repl, text)


def copied_pages(root: Path = ROOT) -> list[Page]:
    """CHANGELOG.md, the detector's model card and the default categories file, as pages."""
    pages = [
        Page(
            "changelog.md",
            _unlink_relative((root / "CHANGELOG.md").read_text(encoding="utf-8"), "docs/"),
            "CHANGELOG.md",
        )
    ]
    card = root / "initcli/detector/models/default.md"
    if card.is_file():
        pages.append(
            Page(
                "detector-model-card.md",
                _unlink_relative(card.read_text(encoding="utf-8")),
                card.relative_to(root).as_posix(),
            )
        )
    categories = root / "bimtools/default_categories.yaml"
    if categories.is_file():
        body = categories.read_text(encoding="utf-8")
        pages.append(
            Page(
                "reference/categories.md",
                "# Default categories\n\nThe mapping `bim-extract` uses without `--categories`, shipped as "
                "`bimtools/default_categories.yaml` (copied here at build time). Copy it, edit it and pass "
                "`--categories my.yaml`; the file's format is in [File formats](file-formats.md).\n\n"
                f"```yaml\n{body}```\n",
                "bimtools/default_categories.yaml",
            )
        )
    return pages


# --------------------------------------------------------------------------------------------------
# Results, from results.jsonl
# --------------------------------------------------------------------------------------------------


def _git(root: Path, *args: str) -> str:
    try:
        done = subprocess.run(
            ["git", *args], cwd=root, capture_output=True, text=True, timeout=30, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return ""
    return done.stdout.strip() if done.returncode == 0 else ""


def read_records(path: Path) -> list[dict]:
    """The trial records of one results.jsonl (blank lines skipped)."""
    records = []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if line.strip():
            try:
                records.append(json.loads(line))
            except json.JSONDecodeError as error:
                raise ValueError(f"{path}:{number}: not JSON: {error.msg}") from None
    return records


def _mean(values: list[float], digits: int = 3) -> str:
    return f"{statistics.fmean(values):.{digits}f}" if values else "-"


def _median(values: list[float], digits: int = 3) -> str:
    return f"{statistics.median(values):.{digits}f}" if values else "-"


def _p95(values: list[float]) -> str:
    """The nearest-rank 95th percentile."""
    if not values:
        return "-"
    ordered = sorted(values)
    return f"{ordered[min(len(ordered) - 1, math.ceil(0.95 * len(ordered)) - 1)]:.3f}"


def _numbers(records: list[dict], key: str) -> list[float]:
    return [float(r[key]) for r in records if isinstance(r.get(key), int | float) and math.isfinite(r[key])]


def _groups(records: list[dict]) -> dict[tuple[str, str, str, str], list[dict]]:
    groups: dict[tuple[str, str, str, str], list[dict]] = {}
    for record in records:
        key = (
            str(record.get("sweep_key", "")),
            str(record.get("sweep_value", "")),
            str(record.get("site", "?")),
            str(record.get("method", "?")),
        )
        groups.setdefault(key, []).append(record)
    return groups


def results_table(records: list[dict]) -> str:
    """Per (sweep value, site, method): trials, success, confident wrong, distance and error."""
    groups = _groups(records)
    sweep = any(k[0] for k in groups)
    head = ["sweep", "value"] if sweep else []
    head += [
        "site",
        "method",
        "trials",
        "success",
        "confident wrong",
        "distance m (mean / median)",
        "error m (mean / median / P95)",
        "error deg (mean)",
        "features (mean)",
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (key, value, site, method), group in groups.items():
        ok = [r for r in group if r.get("success")]
        wrong = sum(1 for r in group if r.get("confident_wrong"))
        cells = [f"`{key}`", value] if sweep else []
        cells += [
            site,
            f"`{method}`",
            str(len(group)),
            f"{len(ok)}/{len(group)} ({100 * len(ok) / len(group):.0f} %)",
            str(wrong),
            f"{_mean(_numbers(ok, 'distance_m'), 1)} / {_median(_numbers(ok, 'distance_m'), 1)}",
            f"{_mean(_numbers(ok, 'error_translation_m'))} / {_median(_numbers(ok, 'error_translation_m'))}"
            f" / {_p95(_numbers(ok, 'error_translation_m'))}",
            _mean(_numbers(ok, "error_rotation_deg"), 2),
            _mean(_numbers(ok, "features"), 1),
        ]
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return "\n".join(lines)


def _figure(records: list[dict], what: str) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = _groups(records)
    labels = [" ".join(x for x in (k[1], k[2], k[3]) if x) for k in groups]
    fig, ax = plt.subplots(figsize=(max(6.0, 0.45 * len(labels) + 2), 3.6), dpi=90)
    if what == "success":
        rates = [100 * sum(1 for r in g if r.get("success")) / len(g) for g in groups.values()]
        wrong = [100 * sum(1 for r in g if r.get("confident_wrong")) / len(g) for g in groups.values()]
        xs = range(len(labels))
        ax.bar([x - 0.2 for x in xs], rates, width=0.4, label="success")
        ax.bar([x + 0.2 for x in xs], wrong, width=0.4, label="confident wrong", color="tab:red")
        ax.set_ylabel("% of trials")
        ax.set_ylim(0, 100)
        ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, fontsize=8, frameon=False)
    else:
        data = [
            _numbers([r for r in g if r.get("success")], "distance_m") or [math.nan] for g in groups.values()
        ]
        ax.boxplot(data)
        ax.set_ylabel("distance to the result, m (successes)")
    ax.set_xticks(range(1, len(labels) + 1) if what != "success" else range(len(labels)))
    ax.set_xticklabels(labels, rotation=60, ha="right", fontsize=7)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    plt.close(fig)
    return buffer.getvalue()


def _provenance(folder: Path, root: Path) -> list[str]:
    lines = []
    info_file = folder / "provenance.json"
    if info_file.is_file():
        info = json.loads(info_file.read_text(encoding="utf-8"))
        if info.get("command"):
            lines.append(f"* Command: `{info['command']}`")
        if info.get("commit"):
            lines.append(
                f"* Code at commit `{info['commit']}`" + (f" ({info['date']})" if info.get("date") else "")
            )
        if info.get("machine"):
            lines.append(f"* Machine: {info['machine']}")
    committed = _git(
        root, "log", "-1", "--format=%h %ad", "--date=short", "--", (folder / "results.jsonl").as_posix()
    )
    if committed:
        lines.append(f"* `results.jsonl` last committed in `{committed}`")
    if not lines:
        lines.append("* No `provenance.json` beside the records: the command and commit are unknown.")
    return lines


def results_pages(root: Path = ROOT, figures: bool = True) -> list[Page]:
    """One page (table and two figures) per results.jsonl under benchmarks/results/, and an index."""
    pages: list[Page] = []
    index = [
        "# Results",
        "",
        "Generated at build time from the `results.jsonl` files committed under "
        "`benchmarks/results/` (one record per trial of `bim-init eval`; fields in "
        "[bim-init eval](../eval.md#outputs)). Nothing on these pages is typed by hand: to update "
        "them, run the command a page names and commit its `results.jsonl`. Success is the "
        "paper's rule (a result within the evaluation's distance limit and error bound); "
        "*confident wrong* counts claimed poses beyond the wrong-pose bound of the evaluation "
        "config ([eval.yaml](../reference/eval-config.md)). Distances and errors are over "
        "successful trials, as in the paper. What each record measured, beside the records "
        "before it: [Measurements](../measurements/index.md); which page cites each record: "
        "`benchmarks/results/README.md`. Superseded records are kept in "
        "`benchmarks/results/archive/` and get no page here.",
        "",
    ]
    nav = []
    files = [folder / "results.jsonl" for folder in record_folders(root)]
    if not files:
        index.append("No results.jsonl is committed under `benchmarks/results/` yet.")
    for path in files:
        folder = path.parent
        name = folder.relative_to(root / RESULTS_DIR).as_posix()
        slug = name.replace("/", "-")
        records = read_records(path)
        sites = sorted({str(r.get("site")) for r in records})
        methods = sorted({str(r.get("method")) for r in records})
        seeds = _numbers(records, "seed")
        seeded = f" (seeds {int(min(seeds))}-{int(max(seeds))})" if seeds else ""
        body = [
            f"# {name}",
            "",
            f"{len(records)} trials{seeded} from `{RESULTS_DIR.as_posix()}/{name}/results.jsonl`: "
            f"sites {', '.join(sites)}; methods {', '.join(f'`{m}`' for m in methods)}.",
            "",
            *_provenance(folder, root),
            "",
            results_table(records),
            "",
        ]
        if figures:
            body += [f"![success and confident wrong, {name}]({slug}-success.png)", ""]
            body += [f"![distance to the result, {name}]({slug}-distance.png)", ""]
            pages.append(Page(f"{RESULTS_PAGES}/{slug}-success.png", lambda r=records: _figure(r, "success")))
            pages.append(
                Page(f"{RESULTS_PAGES}/{slug}-distance.png", lambda r=records: _figure(r, "distance"))
            )
        pages.append(Page(f"{RESULTS_PAGES}/{slug}.md", "\n".join(body), path.relative_to(root).as_posix()))
        index.append(f"* [{name}]({slug}.md): {len(records)} trials")
        nav.append(f"* [{name}]({slug}.md)")
    if (root / REAL_LIDAR).is_file():
        index.append("* [Real laser logs](real-lidar.md): the lidar alone on real robots' logs, beside AMCL")
        nav.insert(0, "* [Real laser logs](real-lidar.md)")
    if (root / WATCH).is_file():
        index.append("* [Lost and found](watch.md): `bim-init watch` on kidnaps spliced from real laser logs")
        nav.insert(1, "* [Lost and found](watch.md)")
    pages.append(Page(f"{RESULTS_PAGES}/index.md", "\n".join(index) + "\n"))
    pages.append(Page(f"{RESULTS_PAGES}/SUMMARY.md", "* [Results](index.md)\n" + "\n".join(nav) + "\n"))
    return pages


def _share(count: int, total: int) -> str:
    return f"{count}/{total} ({100 * count / total:.0f} %)" if total else "-"


def real_lidar_table(rows: list[dict[str, Any]], amcl: bool) -> str:
    """Per log and map kind, then over every log: windows, right, confident wrong, imprecise,
    undecided, mean metres to the claim and seconds per window (and AMCL's right and wrong)."""
    head = ["log", "map", "windows", "right", "confident wrong", "imprecise", "undecided"]
    head += ["m to the claim", "s per window"] + (["AMCL right", "AMCL wrong"] if amcl else [])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    keys = sorted({(str(r["log"]), str(r["map"])) for r in rows})
    keys += [("all", kind) for kind in sorted({str(r["map"]) for r in rows}, reverse=True)]
    for log, kind in keys:
        mine = [r for r in rows if r["map"] == kind and log in ("all", r["log"])]
        n = len(mine)

        def count(outcome: str, key: str = "outcome", group: list[dict[str, Any]] = mine) -> int:
            return sum(r.get(key) == outcome for r in group)

        travel = _mean(
            [float(r["travel_to_claim_m"]) for r in mine if r.get("travel_to_claim_m") is not None], 1
        )
        seconds = _mean([float(r["seconds"]) for r in mine], 1)
        cells = [log if log != "all" else "**all**", kind, str(n), _share(count("right"), n)]
        cells += [str(count("wrong")), str(count("imprecise")), str(count("undecided")), travel, seconds]
        if amcl:
            cells += [_share(count("right", "amcl"), n), str(count("wrong", "amcl"))]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def real_lidar_page(root: Path = ROOT) -> list[Page]:
    """results/real-lidar.md from ``benchmarks/results/real_lidar/real_lidar.json`` (none without it)."""
    path = root / REAL_LIDAR
    if not path.is_file():
        return []
    doc = json.loads(path.read_text(encoding="utf-8"))
    rows = doc["rows"]
    amcl = any("amcl" in r for r in rows)
    info = doc.get("provenance", {})
    body = [
        "# Real laser logs",
        "",
        f"Generated at build time from `{REAL_LIDAR.as_posix()}`, written by "
        f"`{info.get('command', 'python benchmarks/bench_real_lidar.py --out ...')}`"
        f" at commit `{str(info.get('commit', ''))[:7]}` ({info.get('machine', 'this machine')}).",
        "",
        "Real robots' CARMEN laser logs of real buildings (furniture, people, glass; the Radish data"
        " sets' corrected versions, whose poses serve as the truth), each matched against two maps made"
        " from the log: the whole log's occupancy map and a walls-only map (its long straight"
        " structures, as a BIM draws walls, while the scans still see everything else). Windows of"
        f" {info.get('window_m', 60)} m from starts spread over each log, odometry with drift added, are"
        " matched as `bim-init match WINDOW --site SITE` matches them (the camera absent: the lidar"
        " registration replayed along the window). *Right*: unique within"
        f" {info.get('right_m', 0.5)} m and {info.get('right_deg', 5)} degrees of the truth where the claim"
        f" was made; *confident wrong*: unique and more than {info.get('wrong_m', 2)} m or"
        f" {info.get('wrong_deg', 30)} degrees off; *undecided*: no claim, an honest failure. AMCL: global"
        " localisation (5000 particles) on the same windows, odometry and map; right when it converges"
        " within the same bounds. How the benchmark works: `benchmarks/bench_real_lidar.py`.",
        "",
        real_lidar_table(rows, amcl),
        "",
    ]
    for kind, table in doc.get("thresholds", {}).items():
        body += [
            f"## The thresholds on {kind} maps",
            "",
            "Every registration a session would make along the windows (every `registration.every` m),"
            " before the checks that a claim passes (beams through walls, the path in free space, the"
            " scan fit): the best places a pair of `registration.min_fit` (rows) and `registration.margin`"
            " (columns) would let through: right (within the bounds above) / imprecise / wrong (more"
            " than the confident-wrong bounds off). A window stops at its first claim; these go on to"
            " its end, so one window's drifting odometry counts its imprecise places many times.",
            "",
            *table,
            "",
        ]
    return [Page(f"{RESULTS_PAGES}/real-lidar.md", "\n".join(body), REAL_LIDAR.as_posix())]


def watch_table(cases: list[dict[str, Any]], detect_m: float) -> str:
    """Per log and map kind, then over every log: kidnaps, detected within ``detect_m`` m (and the
    median metres), recovered right, wrong; controls, false alarms, a right pose's largest evidence."""
    head = ["log", "map", "kidnaps", f"lost within {detect_m:g} m", "median m to lost", "recovered right"]
    head += ["wrong recoveries", "controls", "false alarms", "largest right evidence"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    keys = sorted({(str(r["log"]), str(r["map"])) for r in cases})
    keys += [("all", kind) for kind in sorted({str(r["map"]) for r in cases}, reverse=True)]
    for log, kind in keys:
        mine = [r for r in cases if r["map"] == kind and log in ("all", r["log"])]
        kidnaps = [r for r in mine if r["kind"] == "kidnap"]
        n = len(kidnaps)
        detected = [float(r["detected_m"]) for r in kidnaps if r.get("detected")]
        cells = [log if log != "all" else "**all**", kind, str(n), _share(len(detected), n)]
        cells += [_median(detected, 1), _share(sum(r.get("recovery") == "right" for r in kidnaps), n)]
        cells += [str(sum(r.get("recovery") == "wrong" for r in kidnaps))]
        cells += [str(sum(r["kind"] == "control" for r in mine)), str(sum(int(r["false_alarms"]) for r in mine))]
        cells += [f"{max(float(r.get('right_statistic', 0.0)) for r in mine):.2f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def watch_page(root: Path = ROOT) -> list[Page]:
    """results/watch.md from ``benchmarks/results/watch/watch.json`` (none without it)."""
    path = root / WATCH
    if not path.is_file():
        return []
    doc = json.loads(path.read_text(encoding="utf-8"))
    info = doc.get("provenance", {})
    body = [
        "# Lost and found on real laser logs",
        "",
        f"Generated at build time from `{WATCH.as_posix()}`, written by"
        f" `{info.get('command', 'python benchmarks/bench_watch.py --out ...')}` at commit"
        f" `{str(info.get('commit', ''))[:7]}` ({info.get('machine', 'this machine')}).",
        "",
        "`bim-init watch` (how it decides: [bim-init watch](../watch.md)) on real robots' CARMEN laser"
        " logs of real buildings, each against two maps made from the log: the whole log's occupancy"
        " map (what a localiser such as AMCL tracks on) and a walls-only map (its long straight"
        " structures, as a building model draws walls). A *kidnap* joins two stretches of one log:"
        f" {info.get('before', 10)} m driven, then the robot carried elsewhere and driven"
        f" {info.get('after', 30)} m, its odometry drifting and unaware; the localiser's pose is right"
        " on the first stretch and carried on by odometry from where it ended, as a tracking localiser"
        f" that did not notice. A *control* is a stretch of {info.get('control_m', 60)} m whose localiser"
        " stays right. *Lost within*: a `lost` event within that much travel after the kidnap;"
        f" *recovered right*: the recovered pose within {info.get('right_m', 0.5)} m and"
        f" {info.get('right_deg', 5)} degrees of the truth; *wrong*: off by more than"
        f" {info.get('wrong_m', 1)} m or {info.get('wrong_deg', 10)} degrees; *false alarms*: `lost` on"
        " a control or before a kidnap. *Largest right evidence*: the largest CUSUM statistic a right"
        f" pose reached, against the threshold {info.get('threshold', 0.8)}.",
        "",
        watch_table(doc["cases"], float(info.get("detect_m", 15))),
        "",
    ]
    return [Page(f"{RESULTS_PAGES}/watch.md", "\n".join(body), WATCH.as_posix())]


# --------------------------------------------------------------------------------------------------
# Record tables inside hand-written pages
# --------------------------------------------------------------------------------------------------

RECORDS_MARK = re.compile(r"^<!--\s*records:\s*(.*?)\s*-->[ \t]*$", re.M)


def record_folders(root: Path = ROOT) -> list[Path]:
    """Every folder under benchmarks/results/ with a results.jsonl, sorted; the archive left out."""
    base = root / RESULTS_DIR
    return [
        path.parent
        for path in sorted(base.glob("**/results.jsonl"))
        if path.parent.relative_to(base).parts[0] != ARCHIVE
    ]


def _site_cell(group: list[dict]) -> str:
    ok = [r for r in group if r.get("success")]
    distance = _mean(_numbers(ok, "distance_m"), 1)
    return f"{len(ok)}/{len(group)}" + (f", {distance} m" if ok else "")


def records_table(names: list[str], root: Path = ROOT, link: str = "../results/") -> str:
    """One row per record folder (and method): its code, trials, success, confident wrong and, per
    site, successes and the mean distance of the successful trials (over every site when a
    record has more than four). Sweep trials and refused starts are left out."""
    rows: list[tuple[str, str, list[dict]]] = []
    for name in names:
        path = root / RESULTS_DIR / name / "results.jsonl"
        if not path.is_file():
            raise ValueError(f"records table: no {path.relative_to(root)}")
        records = [r for r in read_records(path) if not r.get("sweep_key") and not r.get("refused")]
        info_file = path.parent / "provenance.json"
        info = json.loads(info_file.read_text(encoding="utf-8")) if info_file.is_file() else {}
        commit = str(info.get("commit", ""))[:7]
        methods = sorted({str(r.get("method")) for r in records})
        for method in methods:
            rows.append((name, commit, [r for r in records if str(r.get("method")) == method]))
    sites = sorted({str(r.get("site")) for _, _, group in rows for r in group})
    per_site = len(sites) <= 4
    head = ["record", "code", "method", "trials", "success", "confident wrong"]
    head += [f"{site}: success, mean distance" for site in sites] if per_site else ["mean distance"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, commit, group in rows:
        ok = [r for r in group if r.get("success")]
        slug = name.replace("/", "-")
        cells = [
            f"[{name}]({link}{slug}.md)",
            f"`{commit}`" if commit else "",
            f"`{group[0].get('method') if group else ''}`",
            str(len(group)),
            f"{len(ok)}/{len(group)} ({100 * len(ok) / len(group):.0f} %)" if group else "-",
            str(sum(1 for r in group if r.get("confident_wrong"))),
        ]
        if per_site:
            for site in sites:
                at = [r for r in group if str(r.get("site")) == site]
                cells.append(_site_cell(at) if at else "")
        else:
            cells.append(f"{_mean(_numbers(ok, 'distance_m'), 1)} m")
        lines.append("| " + " | ".join(_cell(c) for c in cells) + " |")
    return "\n".join(lines)


def _hand_written(root: Path) -> Iterator[Path]:
    docs = root / "docs"
    for path in sorted(docs.rglob("*.md")):
        if path.relative_to(docs).parts[0] != "gen":
            yield path


def expanded_pages(root: Path = ROOT) -> list[Page]:
    """The hand-written pages holding ``<!-- records: ... -->`` lines, each line replaced by its
    records table (the page's links to the Results pages made relative to the page)."""
    pages = []
    for path in _hand_written(root):
        text = path.read_text(encoding="utf-8")
        if not RECORDS_MARK.search(text):
            continue
        rel = path.relative_to(root / "docs").as_posix()
        link = "../" * rel.count("/") + "results/"
        expanded = RECORDS_MARK.sub(lambda m, to=link: records_table(m.group(1).split(), root, to), text)
        pages.append(Page(rel, expanded, path.relative_to(root).as_posix()))
    return pages


def cited_records(root: Path = ROOT) -> dict[str, list[str]]:
    """Each record folder of ``record_folders`` -> the files that name it: docs pages, README.md,
    CHANGELOG.md (a folder cited nowhere belongs in the archive)."""
    sources = {p.relative_to(root).as_posix(): p.read_text(encoding="utf-8") for p in _hand_written(root)}
    for name in ("README.md", "CHANGELOG.md"):
        if (root / name).is_file():
            sources[name] = (root / name).read_text(encoding="utf-8")
    out: dict[str, list[str]] = {}
    for folder in record_folders(root):
        name = folder.relative_to(root / RESULTS_DIR).as_posix()
        pattern = re.compile(rf"(?<!\w){re.escape(name)}(?!\w)")
        out[name] = [where for where, text in sources.items() if pattern.search(text)]
    return out


def generated_pages(root: Path = ROOT, figures: bool = True) -> list[Page]:
    """Every generated file of the docs build."""
    return (
        api_pages(root)
        + schema_pages(root)
        + copied_pages(root)
        + results_pages(root, figures)
        + real_lidar_page(root)
        + watch_page(root)
        + expanded_pages(root)
    )
