"""``bim-init run --config site.yaml``: a whole initialisation session, on the simulated robot by default."""

from __future__ import annotations

import json
import math
import sys
import time
from contextlib import nullcontext
from datetime import datetime
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.live import Live
from rich.table import Table

from bimkit.checks import check_number
from bimkit.cli import fail, number_option
from bimkit.errors import InputError
from bimkit.outputs import OutputFile, OutputFolder, check_outputs
from bimkit.ownership import never_written_over
from initcli.cli import PROG
from initcli.config import load_config
from initcli.config.building import input_paths
from initcli.core.geometry.se2 import Pose2D
from initcli.session.simulated import RUN_MARKERS, RUN_WRITES, run_simulated

__all__ = ["EXIT_FAILED", "LiveView", "RUN_MARKERS", "SEED_MAX", "parse_start", "result_table", "run"]

EXIT_FAILED = 1
SEED_MAX = 2**32 - 1  # numpy seeds


def parse_start(text: str) -> Pose2D:
    """``--start x,y,yaw_degrees``: finite, x and y within +-1000000 m, yaw within +-3600 degrees."""
    try:
        x, y, yaw = (float(v) for v in text.split(","))
    except ValueError:
        raise InputError(f"--start: expected x,y,yaw_degrees (e.g. 12.5,3.0,90), got {text!r}") from None
    for name, value, bound in (("x", x, 1e6), ("y", y, 1e6), ("yaw", yaw, 3600.0)):
        check_number(value, f"--start {name}", minimum=-bound, maximum=bound)
    return Pose2D(x, y, math.radians(yaw))


class LiveView:
    """A rich table of the session's state, refreshed a few times a second."""

    def __init__(self, console: Console):
        self.console = console
        self.live = Live(self._table({}), console=console, refresh_per_second=4, transient=True)
        self.last = 0.0

    @staticmethod
    def _table(status: dict) -> Table:
        table = Table(title="bim-init run", show_header=False)
        table.add_column("", style="bold")
        table.add_column("")
        table.add_row("time", f"{status.get('t', 0.0):.1f} s")
        table.add_row("state", str(status.get("state", "starting")))
        table.add_row("distance", f"{status.get('distance', 0.0):.1f} m")
        table.add_row("features", str(status.get("features", 0)))
        table.add_row("hypotheses", str(status.get("hypotheses", 0)))
        if "covariance" in status:
            table.add_row("pose sigma", f"{math.sqrt(status['covariance']):.3f} m")
        return table

    def running(self) -> Live:
        """The context in which the view is on screen."""
        return self.live

    def __call__(self, status: dict) -> None:
        now = time.monotonic()
        if now - self.last > 0.2:
            self.last = now
            self.live.update(self._table(status))


def result_table(doc: dict) -> Table:
    table = Table(title="initialisation result")
    table.add_column("")
    table.add_column("value")
    table.add_row("success", "[green]yes[/green]" if doc["success"] else "[red]no[/red]")
    shut = doc.get("shut_in")
    table.add_row("reason", shut["message"] if shut else doc["reason"])
    if doc.get("decided_by"):
        table.add_row("decided by", str(doc["decided_by"]))
    table.add_row("storey", str(doc["storey"]))
    for key in ("coarse_pose", "rectified_pose", "pose"):
        p = doc.get(key)
        table.add_row(
            key.replace("_", " "),
            "-" if p is None else f"x {p['x']:.3f}  y {p['y']:.3f}  yaw {p['yaw_deg']:.2f} deg",
        )
    table.add_row("features detected", str(doc["features_detected"]))
    coarse = "-" if doc["distance_coarse_m"] is None else f"{doc['distance_coarse_m']} m"
    table.add_row("distance to coarse / total", f"{coarse} / {doc['distance_total_m']} m")
    table.add_row("session time", f"{doc['duration_s']} s (simulated in {doc['wall_clock_s']} s)")
    if "error_translation_m" in doc:
        for stage in ("coarse", "rectified", "fine"):
            e, r = doc["error_translation_m"][stage], doc["error_rotation_deg"][stage]
            table.add_row(f"error {stage}", "-" if e is None else f"{e:.3f} m, {r:.2f} deg")
    return table


def run(
    config: Annotated[
        Path,
        typer.Option(
            "--config", metavar="site.yaml", help="Session config (schemas/site_config.schema.json)."
        ),
    ],
    out: Annotated[
        Path | None,
        typer.Option("--out", metavar="DIR", help="Output folder [default: ./runs/<timestamp>/]."),
    ] = None,
    seed: Annotated[
        int | None,
        typer.Option(
            "--seed",
            help="Override sim.seed (0-4294967295).",
            callback=number_option(PROG, minimum=0, maximum=SEED_MAX),
        ),
    ] = None,
    start: Annotated[
        str | None,
        typer.Option("--start", metavar="x,y,yaw", help="Override sim.start (BIM frame, yaw in degrees)."),
    ] = None,
    site: Annotated[
        Path | None,
        typer.Option(
            "--site", metavar="SITE", help="Override site.path (an IFC file or a bim-extract output folder)."
        ),
    ] = None,
    quiet: Annotated[
        bool, typer.Option("--quiet", help="No live view or table; print the summary path only.")
    ] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print summary.json.")] = False,
    force: Annotated[
        bool,
        typer.Option(
            "--force", help="Write into an --out folder that holds other files than a run's (they are kept)."
        ),
    ] = False,
    record: Annotated[
        Path | None,
        typer.Option("--record", metavar="SESSION.mcap", help="Also write the session as a ROS 2 bag."),
    ] = None,
) -> None:
    """Run a whole initialisation session: explore, detect, match, actively explore, rectify, fine-tune."""
    console = Console()
    try:
        cfg = load_config(config)
        if site is not None:
            if not site.exists():
                raise InputError(f"--site: {site} does not exist")
            cfg.site.path = str(site.resolve())  # site.path is relative to the config, --site to here
        start_pose = parse_start(start) if start else None
        the_seed = int(cfg.sim.seed if seed is None else seed)
        target = out or Path("runs") / datetime.now().strftime("%Y%m%d-%H%M%S")
        check_outputs(
            input_paths(cfg),
            [
                OutputFolder(target, "--out", RUN_MARKERS, RUN_WRITES),
                None
                if record is None
                else OutputFile(
                    record, "--record", (".mcap",), owned=never_written_over, kind="new recording"
                ),
            ],
            force,
        )
        if cfg.robot.driver == "rosbridge":
            if start_pose is not None:
                raise InputError("--start: only for the simulated robot (robot.driver: sim)")
            from initcli.session.live import run_live  # the ROS side only when asked for

            doc = run_live(
                cfg,
                target,
                the_seed,
                None if quiet or as_json else LiveView(console),
                warn=lambda line: typer.echo(f"{PROG}: warning: {line}", err=True),
            )
        else:
            view = None if quiet or as_json else LiveView(console)
            doc = run_simulated(
                cfg, target, the_seed, start_pose, view, running=view.running if view else nullcontext
            )
        if record is not None:
            from initcli.ros.bag_writer import record_session

            record_session(target, cfg.site_path(), record)
    except InputError as exc:
        fail(PROG, exc)
    if as_json:
        print(json.dumps(doc, indent=2))
    elif quiet:
        print(target / "summary.json")
        if doc.get("shut_in"):
            print(doc["shut_in"]["message"], file=sys.stderr)
        elif not doc["success"]:
            print(doc["reason"], file=sys.stderr)
    else:
        console.print(result_table(doc))
        console.print(f"wrote {target}/session.jsonl, summary.json, report.png")
    if not doc["success"]:
        raise typer.Exit(EXIT_FAILED)
