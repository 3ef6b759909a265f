"""``bim-init watch``: a tracking localiser's pose checked against the model, and re-initialised when
it is lost (:mod:`initcli.watch`).

Offline, ``bim-init watch BAG_OR_LOG --site SITE`` replays a recording (a ROS bag, read as
``bag2log`` reads it, its camera left unread, or a detection log with ``localiser`` records) with
the decisions a live watch makes; live, ``bim-init watch --config site.yaml`` watches a robot over
rosbridge beside Nav2 (:mod:`initcli.watch.live`).

Exit codes: 0 never lost, or lost and recovered; 1 lost and not recovered; 2 bad input; 130/143
interrupted.
"""

from __future__ import annotations

import json
import math
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Annotated, NoReturn

import typer
from rich.console import Console
from rich.table import Table

from bimkit.cli import fail, number_option
from bimkit.errors import InputError
from bimkit.outputs import OutputFile, check_outputs
from bimkit.ownership import drawn_by_matplotlib
from bimtools.site.load import Site, load_site
from initcli.cli import PROG
from initcli.cli.bag_options import BaseFrame, OdomTopic, ScanTopic
from initcli.cli.progress import count_bar, message_progress
from initcli.config import SessionConfig, load_config
from initcli.config.building import prepare_site
from initcli.io.detection_log import read_log
from initcli.ros.convert import log_or_bag
from initcli.ros.records import Bag2LogOptions
from initcli.watch.records import WatchEvent, WatchState
from initcli.watch.replay import WatchResult, watch_log

__all__ = ["watch"]

PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def watch(
    recording: Annotated[
        Path | None,
        typer.Argument(
            metavar="BAG_OR_LOG",
            help="A recording to replay: a ROS bag, or a detection log with localiser records. None: watch"
            " the live robot of --config over rosbridge.",
            show_default=False,
        ),
    ] = None,
    site: Annotated[
        Path | None,
        typer.Option("--site", metavar="SITE", help="bim-extract OUTDIR (or --config's site.path)."),
    ] = None,
    config: Annotated[
        Path | None, typer.Option("--config", metavar="site.yaml", help="Session config: site, watch, robot.")
    ] = None,
    storey: Annotated[
        str | None, typer.Option("--storey", metavar="NAME", help="The storey the localiser's map is of.")
    ] = None,
    pose_topic: Annotated[
        str | None,
        typer.Option(
            "--pose-topic",
            metavar="T|tf",
            help="The localiser's PoseWithCovarianceStamped [default: watch.pose_topic, /amcl_pose]; tf:"
            " map -> odom on /tf.",
        ),
    ] = None,
    json_out: Annotated[
        bool, typer.Option("--json", help="Print one JSON document: events and checks.")
    ] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot", metavar="FILE.png", help="Draw the localiser's track, the checks and the events."
        ),
    ] = None,
    duration: Annotated[
        float,
        typer.Option(
            "--duration",
            metavar="S",
            help="Live: stop after this many seconds (0: until Ctrl-C).",
            callback=number_option(PROG, minimum=0, maximum=1e7),
        ),
    ] = 0.0,
    odom_topic: OdomTopic = None,
    scan_topic: ScanTopic = None,
    base_frame: BaseFrame = None,
) -> None:
    """Check a localiser's pose against the model as the robot drives; re-initialise it when lost.

    Exit codes: 0 never lost, or lost and recovered; 1 lost and not recovered; 2 bad input.
    """
    try:
        cfg = load_config(config) if config is not None else None
        if recording is None:
            if cfg is None:
                raise InputError("give a recording (BAG_OR_LOG) to replay, or --config to watch a live robot")
            _live(cfg, storey, pose_topic, duration, json_out)
        if site is None and cfg is None:
            raise InputError("--site SITE (or --config site.yaml) is needed to replay a recording")
        inputs = [recording, site, config]
        plots = (
            OutputFile(plot, "--plot", PLOT_SUFFIXES, owned=drawn_by_matplotlib, kind="plot")
            if plot
            else None
        )
        check_outputs(inputs, [plots])
        topic = pose_topic if pose_topic is not None else (cfg.watch.pose_topic if cfg is not None else None)
        options = Bag2LogOptions(
            odom_topic=odom_topic,
            scan_topic=scan_topic,
            base_frame=base_frame,
            pose_topic=topic,
            lidar_only=True,
        )
        with tempfile.TemporaryDirectory(prefix="bim-init-watch-") as tmp:
            model = _site(site, cfg, Path(tmp))
            with message_progress("reading") as progress, log_or_bag(recording, options, progress) as path:
                log = read_log(path)
                result = _replay(log, model, storey if storey is not None else _config_storey(cfg), cfg)
    except InputError as exc:
        fail(PROG, exc)
    if json_out:
        typer.echo(json.dumps(result.as_dict(), indent=1))
    else:
        print_result(result, Console(stderr=False))
    if plot is not None:
        from initcli.watch.plot import plot_watch

        try:
            plot_watch(result, model, plot)
        except OSError as exc:
            fail(PROG, f"{plot}: cannot write the plot: {exc.strerror or exc}")
    raise typer.Exit(result.exit_code)


def _live(
    cfg: SessionConfig, storey: str | None, pose_topic: str | None, duration: float, json_out: bool
) -> NoReturn:
    """Watch the live robot; each event a line as it happens (JSON with ``--json``), the exit code
    of the state at the end."""
    from initcli.watch.live import watch_live

    def echo(event: WatchEvent) -> None:
        if json_out:
            typer.echo(json.dumps(event.as_dict()))
        else:
            pose = (
                ""
                if event.pose is None
                else f" at {event.pose.x:.2f} {event.pose.y:.2f} {math.degrees(event.pose.yaw):.1f}°"
            )
            typer.echo(f"{event.t:.2f} s, {event.travel:.1f} m: {event.kind}{pose}: {event.reason}")

    result = watch_live(cfg, storey, pose_topic, duration, echo)
    typer.echo(result.summary(), err=json_out)
    raise typer.Exit(result.exit_code)


def _site(site: Path | None, cfg: SessionConfig | None, workdir: Path) -> Site:
    if site is not None:
        return load_site(site)
    assert cfg is not None
    return prepare_site(cfg, workdir)


def _config_storey(cfg: SessionConfig | None) -> str | None:
    return None if cfg is None or cfg.site.storey == "auto" else cfg.site.storey


def _replay(log: object, site: Site, storey: str | None, cfg: SessionConfig | None) -> WatchResult:
    from initcli.io.log_records import DetectionLog

    assert isinstance(log, DetectionLog)
    params = (cfg or SessionConfig()).watch
    registration = (cfg or SessionConfig()).registration
    verification = (cfg or SessionConfig()).verification
    with count_bar("watch") as bar:
        task = bar.add_task("records", total=None)
        return watch_log(
            log,
            site,
            storey,
            params,
            replace(registration, enabled=True),
            verification,
            lambda done, total: bar.update(task, completed=done, total=total),
        )


def print_result(result: WatchResult, console: Console) -> None:
    """The events as a table, then the summary line (last line)."""
    if result.events:
        table = Table(title=f"Events (storey {result.storey}, robot clock)", title_justify="left")
        for col in ("t [s]", "travel [m]", "kind", "pose x y yaw", "reason"):
            table.add_column(col, justify="right" if col[0] in "tp" and col != "kind" else "left")
        for e in result.events:
            pose = "-" if e.pose is None else f"{e.pose.x:.2f} {e.pose.y:.2f} {math.degrees(e.pose.yaw):.1f}°"
            table.add_row(f"{e.t:.2f}", f"{e.travel:.1f}", str(e.kind), pose, e.reason)
        console.print(table)
    style = "bold red" if result.state is WatchState.LOST else "bold"
    console.print(result.summary(), style=style, highlight=False)
