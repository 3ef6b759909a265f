"""``bim-extract MODEL.ifc``: per-storey features, wall outlines, maps and previews from an IFC model."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TaskID, TextColumn, TimeElapsedColumn
from rich.table import Table

from bimkit.cli import number_option
from bimkit.errors import EXIT_BAD_INPUT, InputError
from bimkit.outputs import OutputFolder, check_outputs
from bimtools import __version__
from bimtools.settings import (
    DEFAULT_RESOLUTION,
    DEFAULT_SECTION_HEIGHT,
    RESOLUTION_RANGE,
    SECTION_HEIGHT_RANGE,
)

__all__ = ["LazyProgress", "PROG", "app", "extract", "main", "summary_table"]

PROG = "bim-extract"

app = typer.Typer(add_completion=False, pretty_exceptions_enable=False, rich_markup_mode=None)
err = Console(stderr=True)
out = Console()


class LazyProgress:
    """A rich progress bar that only appears once the work has taken more than a second, and only
    on a terminal (a log file gets no bar and no stray line from it)."""

    def __init__(self, label: str, delay: float = 1.0):
        self.label = label
        self.delay = delay
        self.start = time.monotonic()
        self.progress: Progress | None = None
        self.task: TaskID | None = None

    def __call__(self, done: int, total: int) -> None:
        if self.progress is None:
            if not err.is_terminal or time.monotonic() - self.start < self.delay:
                return
            self.progress = Progress(
                TextColumn(self.label),
                BarColumn(),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                console=err,
                transient=True,
            )
            self.progress.start()
            self.task = self.progress.add_task(self.label, total=total)
        if self.task is not None:
            self.progress.update(self.task, completed=done, total=total)

    def close(self) -> None:
        if self.progress is not None:
            self.progress.stop()


def summary_table(manifest) -> Table:
    categories: list[str] = []
    for s in manifest.storeys:
        categories += [c for c in s.counts if c not in categories]
    table = Table(
        title=f"{manifest.source_file} ({manifest.schema}, {manifest.application or 'unknown tool'})"
    )
    table.add_column("Storey")
    table.add_column("Elevation (m)", justify="right")
    for c in categories:
        table.add_column(c, justify="right")
    table.add_column("Map")
    for s in manifest.storeys:
        table.add_row(
            s.name, f"{s.elevation:.2f}", *[str(s.counts.get(c, 0)) for c in categories], s.map_yaml or ""
        )
    return table


@app.command()
def extract(
    model: Annotated[
        Path,
        typer.Argument(
            metavar="MODEL.ifc|MAP.yaml",
            help="IFC model (IFC2X3, IFC4, IFC4X3), or a ROS map_server / Nav2 map YAML (its PGM or "
            "PNG beside it)",
            show_default=False,
        ),
    ],
    outdir: Annotated[
        Path | None, typer.Option("-o", "--outdir", help="output folder [default: ./<model-stem>_site/]")
    ] = None,
    storey: Annotated[
        str | None, typer.Option(help="storey name, or 'all' [default: storeys with features]")
    ] = None,
    categories: Annotated[
        Path | None, typer.Option(help="categories YAML overriding the shipped default")
    ] = None,
    section_height: Annotated[
        float,
        typer.Option(
            help="cut height above each storey's elevation (m, (0, 10])",
            callback=number_option(PROG, **SECTION_HEIGHT_RANGE),
        ),
    ] = DEFAULT_SECTION_HEIGHT,
    resolution: Annotated[
        float,
        typer.Option(
            help="occupancy grid resolution (m/pixel, [0.005, 1])",
            callback=number_option(PROG, **RESOLUTION_RANGE),
        ),
    ] = DEFAULT_RESOLUTION,
    features: Annotated[
        Path | None,
        typer.Option(
            "--features",
            metavar="FILE.csv",
            help="with a map: the features (paper Table 1 columns, as features.csv) to put in the site",
        ),
    ] = None,
    force: Annotated[
        bool,
        typer.Option(
            "--force", help="write into an output folder that holds other files than a site's (they are kept)"
        ),
    ] = False,
    as_json: Annotated[
        bool, typer.Option("--json", help="print the manifest (site.json) instead of a table")
    ] = False,
    version: Annotated[bool, typer.Option("--version", help="print the version and exit")] = False,
) -> None:
    """Extract doors, lifts and stairs (paper Table 1), wall outlines, ROS maps and previews per storey.

    Given a map YAML instead, write it as a site of one storey named after the file: the map as
    given, walls from its occupied cells, the features of --features (else none)."""
    from bimtools.extract.output import SITE_MARKERS, SITE_WRITES, write_site
    from bimtools.extract.pipeline import extract_site
    from bimtools.ifc.categories import load_categories

    if version:
        out.print(f"bim-extract {__version__}")
        return
    from bimtools.extract.from_map import is_map_file

    if is_map_file(model):
        _extract_map(model, outdir, storey, categories, section_height, resolution, features, force, as_json)
        return
    if features is not None:
        _fail(
            f"--features {features}: applies to a map (MAP.yaml); an IFC model's features come from the model"
        )
    progress = LazyProgress("geometry")
    try:
        target = outdir if outdir is not None else Path.cwd() / f"{model.stem}_site"
        check_outputs(
            [model, categories], [OutputFolder(target, "-o/--outdir", SITE_MARKERS, SITE_WRITES)], force
        )
        category_set = load_categories(categories) if categories is not None else load_categories()
        site = extract_site(model, category_set, storey, section_height, resolution, progress=progress)
        progress.close()
        manifest = write_site(target, site)
        for warning in site.warnings:
            print(f"bim-extract: warning: {warning}", file=sys.stderr)
    except InputError as exc:
        progress.close()
        print(f"{PROG}: error: {' '.join(str(exc).split())}", file=sys.stderr)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    if as_json:
        for note in site.notes:
            print(f"bim-extract: note: {note}", file=sys.stderr)
        if site.skipped:
            print(f"bim-extract: skipped: {site.skipped_summary()}", file=sys.stderr)
        print(json.dumps(manifest.to_dict(), indent=2))
    else:
        out.print(summary_table(manifest))
        for note in site.notes:
            out.print(f"note: {note}", highlight=False)
        if site.skipped:
            out.print(f"skipped: {site.skipped_summary()} (the warnings say which)", highlight=False)
        out.print(f"wrote {len(manifest.files)} files to {target}")


def _fail(message: str) -> None:
    print(f"{PROG}: error: {' '.join(message.split())}", file=sys.stderr)
    raise typer.Exit(EXIT_BAD_INPUT)


def _extract_map(
    model: Path,
    outdir: Path | None,
    storey: str | None,
    categories: Path | None,
    section_height: float,
    resolution: float,
    features: Path | None,
    force: bool,
    as_json: bool,
) -> None:
    """``bim-extract MAP.yaml``: the map as a one-storey site (bimtools.extract.from_map)."""
    from bimtools.extract.from_map import read_map_site, trace_map_site, write_map_site
    from bimtools.extract.output import SITE_MARKERS, SITE_WRITES
    from bimtools.site.occupancy_map import map_image_path

    try:
        if storey is not None and storey not in ("all", model.stem):
            raise InputError(
                f"--storey {storey!r}: a map has one storey, named after its file: {model.stem!r}"
            )
        target = outdir if outdir is not None else Path.cwd() / f"{model.stem}_site"
        check_outputs(
            [model, map_image_path(model) if model.is_file() else None, categories, features],
            [OutputFolder(target, "-o/--outdir", SITE_MARKERS, SITE_WRITES)],
            force,
        )
        names: tuple[str, ...] = ("Door", "Lift", "Stairs")
        if categories is not None:
            from bimtools.ifc.categories import load_categories

            names = tuple(load_categories(categories).names)
        site = read_map_site(model, features, names, section_height)
        if resolution != DEFAULT_RESOLUTION and abs(resolution - site.grid.resolution) > 1e-12:
            raise InputError(
                f"--resolution {resolution:g}: a map keeps its own resolution ({site.grid.resolution:g} m)"
            )
        manifest = write_map_site(target, trace_map_site(site))
    except InputError as exc:
        _fail(str(exc))
    if as_json:
        print(json.dumps(manifest.to_dict(), indent=2))
    else:
        out.print(summary_table(manifest))
        out.print(
            f"note: {len(site.walls)} wall surfaces and {len(site.obstacles)} obstacles from the occupied "
            f"cells; {len(site.features)} features",
            highlight=False,
        )
        out.print(f"wrote {len(manifest.files)} files to {target}")


def main() -> None:
    from bimkit.cli import run_cli

    run_cli(app, "bim-extract")


if __name__ == "__main__":
    main()
