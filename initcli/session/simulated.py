"""A session on the simulated robot: assembled from its config (:func:`sim_session`, shared by
``bim-init run`` and the evaluation's trials) and run into an output folder with its summary and
report (:func:`run_simulated`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bimkit.atomic import staged_directory
from bimtools.site.load import Site
from initcli.config import SessionConfig, config_to_dict
from initcli.config.building import choose_storey, prepare_site, prepare_world
from initcli.core.geometry.se2 import Pose2D
from initcli.session.outputs import render_report, report_title, summary_document, write_summary
from initcli.session.result import CANNOT_LEAVE, SessionResult
from initcli.session.runner import Observer, Session
from initcli.sim.build import SimSetup, build_sim

__all__ = ["RUN_MARKERS", "RUN_WRITES", "SESSION_RNG_OFFSET", "SimSession", "run_simulated", "sim_session"]

RUN_MARKERS = ("summary.json",)  # a folder holding one was written by bim-init run
RUN_WRITES = ("session.jsonl", "summary.json", "report.png", "site", "world")  # what a run writes there


SESSION_RNG_OFFSET = 7919  # the session's own generator (particle filter) is seeded apart from the world


@dataclass
class SimSession:
    """A session on the simulated robot, and what it was built from."""

    session: Session
    setup: SimSetup
    simulated_storey: str  # the storey simulated (the session may match against every storey)


def sim_session(
    config: SessionConfig,
    site: Site,
    seed: int,
    start: Pose2D | None = None,
    log_path: Path | None = None,
    observer: Observer | None = None,
    meta_source: str = "bim-init run",
    world: Site | None = None,
) -> SimSession:
    """The session of ``config`` on the simulated robot of ``seed`` (``start`` None: the config's
    start, else a random one), logging to ``log_path`` (None: no log file); ``world``: the building
    the robot lives in when it is not the BIM (``sim.world``)."""
    simulated, matched = choose_storey(config, site)
    setup = build_sim(config, site, simulated, seed, start, world_site=world)
    rng = np.random.default_rng(seed + SESSION_RNG_OFFSET)
    session = Session(config, site, matched, setup.driver, log_path, rng, observer, meta_source)
    if setup.enclosed and config.sim.refuse_enclosed:
        session.cannot_leave = CANNOT_LEAVE
    return SimSession(session, setup, simulated)


def run_simulated(
    config: SessionConfig,
    out: Path,
    seed: int,
    start: Pose2D | None = None,
    observer: Observer | None = None,
    running: Callable[[], AbstractContextManager[object]] = nullcontext,
) -> dict:
    """Run one session on the simulated robot into ``out`` (staged: nothing half-written on
    failure): ``session.jsonl``, ``summary.json`` and ``report.png``. ``observer`` sees the state
    while it runs, inside the context ``running`` gives (a live console view). Returns the summary."""
    with staged_directory(out, RUN_MARKERS) as stage:
        site = prepare_site(config, stage)
        world = prepare_world(config, stage)
        built = sim_session(
            config,
            site,
            seed,
            start,
            stage / "session.jsonl",
            observer=observer,
            meta_source=f"bim-init run (sim, seed {seed})",
            world=world,
        )
        session, setup = built.session, built.setup
        with running():
            result: SessionResult = session.run()
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
            report_title(result, Path(config.site.path).name),
            world_segments=setup.world.static,
        )
    return doc
