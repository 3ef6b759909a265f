"""initcli.cli.eval: the terminal table that folds each (paper) column into its neighbour."""

from __future__ import annotations

from rich.console import Console
from rich.table import Table

from initcli.cli.eval import _rich_table
from initcli.eval.tables import NONE


def _text(table: Table) -> str:
    console = Console(record=True, width=200, color_system=None)
    console.print(table)
    return console.export_text()


def test_rich_table_folds_paper_columns() -> None:
    header = ["site", "method", "success", "(paper)", "distance"]
    rows = [["a", "bim", "90%", "85%", "12.0"], ["b", "bim", "80%", NONE, "9.0"]]
    table = _rich_table("T", header, rows)
    assert [c.header for c in table.columns] == ["site", "method", "success", "distance"]
    text = _text(table)
    assert "90% (85%)" in text
    line_b = next(line for line in text.splitlines() if "80%" in line)
    assert " b " in line_b and "(" not in line_b
