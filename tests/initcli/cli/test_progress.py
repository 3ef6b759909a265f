"""The counting progress bar of the command faces (initcli.cli.progress)."""

from __future__ import annotations

from initcli.cli.progress import count_bar


def test_count_bar_is_transient_on_stderr_and_counts() -> None:
    bar = count_bar("bag2log")
    assert bar.live.transient and bar.console.stderr
    with bar:
        task = bar.add_task("messages", total=4)
        bar.update(task, completed=3)
        assert bar.tasks[0].completed == 3 and bar.tasks[0].total == 4
