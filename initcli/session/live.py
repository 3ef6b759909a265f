"""A session on a live robot behind a rosbridge server (``robot.driver: rosbridge``): its state goes
to ``/bim_init/state`` and its hypotheses to ``/bim_init/hypotheses`` while it runs, the result to
``/initialpose`` (Nav2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bimkit.atomic import staged_directory
from initcli.config import SessionConfig, camera_of, config_to_dict
from initcli.core.geometry import Pose2D
from initcli.ros.nav2 import session_initial_pose
from initcli.ros.rosbridge import RosbridgeLink
from initcli.ros.rosbridge_driver import RosbridgeDriver
from initcli.session.outputs import summary_document, write_summary
from initcli.session.result import MatchStep
from initcli.session.runner import Observer, Session
from initcli.session.simulated import RUN_MARKERS, SESSION_RNG_OFFSET
from initcli.site import choose_storey, prepare_site

__all__ = ["run_live"]


def run_live(config: SessionConfig, out: Path, seed: int, view: Observer | None = None) -> dict:
    """``robot.driver: rosbridge``: the session on the real robot behind a rosbridge server; its state
    goes to ``/bim_init/state`` while it runs and the result to ``/initialpose`` (Nav2)."""
    r = config.robot
    with staged_directory(out, RUN_MARKERS) as stage:
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
