"""Every command's help, and the survey's table, read whole at 80 columns: no option name, metavar
or summary cut ("…", a summary ending in "..."), no stray space before a full stop (a help text's
"[default: ...]" taken for markup and dropped), no line wider than the terminal."""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest
import typer
from rich.console import Console
from typer.testing import CliRunner

from bimtools.cli import app as extract_app
from initcli.cli.main import app as init_app
from initcli.cli.survey import _survey_table, _table_row

WIDTH = 80
runner = CliRunner()


def _paths(command, path: tuple[str, ...] = ()) -> Iterator[tuple[str, ...]]:
    yield path
    for name, sub in sorted(getattr(command, "commands", {}).items()):
        yield from _paths(sub, (*path, name))


COMMANDS = [("bim-init", p) for p in _paths(typer.main.get_command(init_app))] + [("bim-extract", ())]


def _problems(text: str) -> list[str]:
    problems = []
    for n, line in enumerate(text.splitlines(), 1):
        if "…" in line:
            problems.append(f"line {n}: cut with an ellipsis: {line!r}")
        if re.search(r"\s\.(\s|$)", line):
            problems.append(f"line {n}: space before a full stop: {line!r}")
        if len(line) > WIDTH:
            problems.append(f"line {n}: {len(line)} columns: {line!r}")
        if not line.startswith("Usage:") and re.search(r"\w\.\.\.$", line):
            problems.append(f"line {n}: summary cut with '...': {line!r}")
    return problems


@pytest.mark.parametrize(("prog", "path"), COMMANDS, ids=lambda v: " ".join(v) if isinstance(v, tuple) else v)
def test_help_is_whole_at_80_columns(prog: str, path: tuple[str, ...]) -> None:
    app = init_app if prog == "bim-init" else extract_app
    result = runner.invoke(app, [*path, "--help"], env={"COLUMNS": str(WIDTH)}, terminal_width=WIDTH)
    assert result.exit_code == 0, result.output
    assert "Usage:" in result.output
    assert _problems(result.output) == []


def test_every_option_name_and_metavar_is_in_the_help() -> None:
    """The long names that rich's panels cut (``--detections-to…``) are there in full."""
    result = runner.invoke(init_app, ["match", "--help"], env={"COLUMNS": str(WIDTH)}, terminal_width=WIDTH)
    for whole in ("--detections-topic T", "--camera-info-topic T", "--landmark-window M", "vision_msgs/"):
        assert whole in result.output
    assert (
        "Output folder [default: ./runs/<timestamp>/]."
        in runner.invoke(init_app, ["run", "--help"], terminal_width=WIDTH).output
    )


def test_survey_table_is_whole_at_80_columns() -> None:
    """Long and non-Latin storey names wrap; no header or cell is cut."""
    entry = {
        "samples": 12345,
        "area_m2": 12345.0,
        "unique_within": {"5m": 1.0, "10m": 0.5, "20m": 1.0},
        "median_distance_m": None,
        "never_unique_area_m2": 12345.0,
    }
    table = _survey_table()
    names = ["Уровень 1", "Level 2 - offices and meeting rooms", "Erdgeschoss_Haupttreppenhaus_Nord [A]"]
    for name in names:
        table.add_row(*_table_row(name, entry))
    console = Console(width=WIDTH, record=True, color_system=None)
    console.print(table)
    text = console.export_text()
    assert _problems(text) == []
    headers = " ".join(line for line in text.splitlines() if line.startswith("┃"))
    for word in ("storey", "starts", "area", "<=5 m", "<=20 m", "median", "never", "unique", "m2"):
        assert word in headers, word
    storey_column = "".join(line.split("│")[1].strip() for line in text.splitlines() if line.startswith("│"))
    for name in names:
        assert name.replace(" ", "") in storey_column.replace(" ", ""), name
