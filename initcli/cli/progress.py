"""Progress displays of the command faces: the bar of those that count work items (bag messages,
rendered images), and detector training's epochs with their validation tables."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

if TYPE_CHECKING:
    from initcli.detector.metrics import Metrics

__all__ = ["TrainingProgress", "count_bar", "message_progress", "metrics_table"]


def count_bar(label: str) -> Progress:
    """A transient bar on stderr: ``label``, the bar, done / total and the time left."""
    return Progress(
        TextColumn(label),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        transient=True,
    )


@contextmanager
def message_progress(label: str = "bag2log") -> Iterator[Callable[[int, int], None] | None]:
    """A ``progress(done, total)`` callback drawing a bar of bag messages on a terminal, else None."""
    if not sys.stderr.isatty():
        yield None
        return
    with count_bar(label) as bar:
        task = bar.add_task("messages", total=None)
        yield lambda done, total: bar.update(task, completed=done, total=total)


def metrics_table(metrics: Metrics, title: str) -> Table:
    """Precision, recall and AP@0.5 per class, and the mean over the classes."""
    table = Table(title=title or None, title_justify="left")
    for col in ("class", "instances", "precision", "recall", "AP@0.5"):
        table.add_column(col, justify="left" if col == "class" else "right")

    def f(v: float | None) -> str:
        return "-" if v is None else f"{v:.3f}"

    for c in metrics.classes:
        table.add_row(c.name, str(c.instances), f(c.precision), f(c.recall), f(c.ap50))
    table.add_row(
        "all", str(sum(c.instances for c in metrics.classes)), "", "", f(metrics.map50), style="bold"
    )
    return table


class TrainingProgress:
    """Training on the terminal: the data and device at the start, a bar per epoch with the running
    losses (on stderr), and each epoch's validation table."""

    def __init__(self, console: Console, epochs: int) -> None:
        self.console = console
        self.epochs = epochs
        self.progress = Progress(
            TextColumn("[progress.description]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[losses]}"),
            TimeElapsedColumn(),
            console=Console(stderr=True),
        )
        self.state: dict = {}

    def on_event(self, kind: str, info: dict) -> None:
        """The training's callback: 'start', 'step' and 'epoch' events."""
        if kind == "start":
            ds = info["dataset"]
            self.console.print(
                f"data: {len(ds.train)} train / {len(ds.val)} val images, classes {ds.names}; "
                f"device {info['device']}; {info['params']:,} parameters"
            )
            self.state["steps"] = info["steps_per_epoch"]
        elif kind == "step":
            self._step(info)
        elif kind == "epoch":
            self._epoch(info)

    def _step(self, info: dict) -> None:
        state, progress = self.state, self.progress
        epoch = info["epoch"]
        if state.get("epoch") != epoch:
            if "task" in state:
                progress.remove_task(state["task"])
            state["epoch"] = epoch
            label = f"epoch {epoch + 1}/{self.epochs}"
            state["task"] = progress.add_task(label, total=state["steps"], losses="")
        progress.update(
            state["task"],
            advance=1,
            losses=f"loss {info['loss']:.3f} hm {info['hm']:.3f} box {info['box']:.3f}",
        )

    def _epoch(self, info: dict) -> None:
        r = info["record"]
        if info["metrics"] is not None:
            self.progress.console.print(
                metrics_table(info["metrics"], f"epoch {r.epoch}: loss {r.loss:.3f}, {r.seconds:.0f} s, val")
            )
        else:
            line = f"epoch {r.epoch}: loss {r.loss:.3f}, {r.seconds:.0f} s (no val split)"
            self.progress.console.print(line)
