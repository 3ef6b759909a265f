"""``bim-init run --config site.yaml``: a whole initialisation session, on the simulated robot by default."""

from __future__ import annotations

import json
import math
import time
from datetime import datetime
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.live import Live
from rich.table import Table

from bimkit.atomic import staged_directory
from bimkit.checks import check_number, check_output_dir, check_output_file
from bimkit.cli import fail, number_option
from bimkit.errors import InputError
from initcli.cli import PROG
from initcli.config import SessionConfig, config_to_dict, load_config
from initcli.core.geometry import Pose2D
from initcli.session.outputs import render_report, summary_document, write_summary
from initcli.session.result import MatchStep, SessionResult
from initcli.session.setup import prepare_site, prepare_world, sim_session

EXIT_FAILED = 1
SEED_MAX = 2**32 - 1  # numpy seeds
RUN_MARKERS = ("summary.json",)  # an --out folder holding one was written by bim-init run


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
    table.add_row("reason", doc["reason"])
    table.add_row("storey", str(doc["storey"]))
    for key in ("coarse_pose", "rectified_pose", "pose"):
        p = doc.get(key)
        table.add_row(
            key.replace("_", " "),
            "-" if p is None else f"x {p['x']:.3f}  y {p['y']:.3f}  yaw {p['yaw_deg']:.2f} deg",
        )
    table.add_row("features detected", str(doc["features_detected"]))
    table.add_row("distance to coarse / total", f"{doc['distance_coarse_m']} m / {doc['distance_total_m']} m")
    table.add_row("session time", f"{doc['duration_s']} s (simulated in {doc['wall_clock_s']} s)")
    if "error_translation_m" in doc:
        for stage in ("coarse", "rectified", "fine"):
            e, r = doc["error_translation_m"][stage], doc["error_rotation_deg"][stage]
            table.add_row(f"error {stage}", "-" if e is None else f"{e:.3f} m, {r:.2f} deg")
    return table


def run_session(
    config: SessionConfig, out: Path, seed: int, start: Pose2D | None, quiet: bool, console: Console
) -> dict:
    """Run one session into ``out`` (staged: nothing half-written on failure). Returns the summary."""
    with staged_directory(out) as stage:
        site = prepare_site(config, stage)
        world = prepare_world(config, stage)
        view = None if quiet else LiveView(console)
        built = sim_session(
            config,
            site,
            seed,
            start,
            stage / "session.jsonl",
            observer=view,
            meta_source=f"bim-init run (sim, seed {seed})",
            world=world,
        )
        session, setup = built.session, built.setup
        if view is not None:
            with view.live:
                result: SessionResult = session.run()
        else:
            result = session.run()
        extra = {
            "seed": seed,
            "start_pose": {
                "x": setup.start.x,
                "y": setup.start.y,
                "yaw_deg": round(math.degrees(setup.start.yaw), 3),
            },
            "config": config_to_dict(config),
        }
        doc = summary_document(result, simulated=True, extra=extra)
        write_summary(stage / "summary.json", doc)
        render_report(
            stage / "report.png",
            result,
            site.storeys[result.storey or built.simulated_storey],
            f"{config.site.path}: {'success' if result.success else 'failure'} - {result.reason}",
            world_segments=setup.world.static,
        )
    return doc


def run_live_session(config: SessionConfig, out: Path, seed: int, quiet: bool, console: Console) -> dict:
    """``robot.driver: rosbridge``: the session on the real robot behind a rosbridge server; its state
    goes to ``/bim_init/state`` while it runs and the result to ``/initialpose`` (Nav2)."""
    import numpy as np

    from initcli.ros.nav2 import session_initial_pose
    from initcli.ros.rosbridge import RosbridgeLink
    from initcli.ros.rosbridge_driver import RosbridgeDriver
    from initcli.session.runner import Session
    from initcli.session.setup import SESSION_RNG_OFFSET, camera_of, choose_storey

    r = config.robot
    with staged_directory(out) as stage:
        site = prepare_site(config, stage)
        _, matched = choose_storey(config, site)
        link = RosbridgeLink(r.rosbridge.host, r.rosbridge.port)
        camera, mount = camera_of(config)
        driver = RosbridgeDriver(
            link,
            camera,
            mount,
            r.rosbridge,
            drive=r.drive,
            depth_window=int(config.camera.depth_window),
            max_linear=r.max_linear,
            max_angular=r.max_angular,
        )
        view = None if quiet else LiveView(console)
        last_state: list[str] = []
        published = [0]  # match steps whose hypotheses went out
        steps: list[MatchStep] = []  # the session's match steps (bound below)

        def observe(update: dict) -> None:
            if view is not None:
                view(update)
            if not last_state or update["state"] != last_state[-1]:
                last_state.append(update["state"])
                driver.publish_state(str(update["state"]))
            if len(steps) > published[0]:
                published[0] = len(steps)
                step = steps[-1]
                driver.publish_hypotheses(step.t, [Pose2D(*p) for p in step.poses])

        session = Session(
            config,
            site,
            matched,
            driver,
            stage / "session.jsonl",
            np.random.default_rng(seed + SESSION_RNG_OFFSET),
            observe,
            meta_source=f"bim-init run (rosbridge ws://{r.rosbridge.host}:{r.rosbridge.port})",
        )
        steps = session.result.match_steps
        try:
            result = session.run()
        finally:
            driver.stop()
        doc = summary_document(result, simulated=False, extra={"config": config_to_dict(config)})
        write_summary(stage / "summary.json", doc)
        if result.success:
            driver.publish_initial_pose(session_initial_pose(doc, stage / "session.jsonl"))
            driver.publish_state("initialised")
        driver.close()
    return doc


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
    quiet: Annotated[
        bool, typer.Option("--quiet", help="No live view or table; print the summary path only.")
    ] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print summary.json.")] = False,
    force: Annotated[
        bool, typer.Option("--force", help="Replace an --out folder that holds other files than a run's.")
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
        start_pose = parse_start(start) if start else None
        the_seed = int(cfg.sim.seed if seed is None else seed)
        target = out or Path("runs") / datetime.now().strftime("%Y%m%d-%H%M%S")
        check_output_dir(target, "--out", RUN_MARKERS, force)
        if record is not None:
            check_output_file(record, "--record")
        if cfg.robot.driver == "rosbridge":
            if start_pose is not None:
                raise InputError("--start: only for the simulated robot (robot.driver: sim)")
            doc = run_live_session(cfg, target, the_seed, quiet or as_json, console)
        else:
            doc = run_session(cfg, target, the_seed, start_pose, quiet or as_json, console)
        if record is not None:
            from initcli.ros.bag_writer import record_session

            record_session(target, cfg.site_path(), record)
    except InputError as exc:
        fail(PROG, exc)
    if as_json:
        print(json.dumps(doc, indent=2))
    elif quiet:
        print(target / "summary.json")
    else:
        console.print(result_table(doc))
        console.print(f"wrote {target}/session.jsonl, summary.json, report.png")
    if not doc["success"]:
        raise typer.Exit(EXIT_FAILED)
