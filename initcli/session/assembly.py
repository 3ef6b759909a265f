"""A session's collaborators, built from its config in one place: each takes its settings at
construction (none is patched afterwards, none keeps a default of its own)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bimtools.site.load import Site
from initcli.config import SessionConfig, followed_side, match_options, wall_follow_params
from initcli.config.building import twin_reason
from initcli.config.matching import MatchOptions
from initcli.core.features.classes import ClassMap
from initcli.core.navigation.wall_following import WallFollowParams
from initcli.core.verify.checks import CameraView
from initcli.drivers.base import RobotDriver
from initcli.io.detection_log import Meta
from initcli.match.landmarks import site_tracker
from initcli.match.recorded import session_meta_settings
from initcli.session.claims import ClaimChecks
from initcli.session.escapes import Escapes
from initcli.session.exploration import ActiveExploration
from initcli.session.fine_tuning import FineStage
from initcli.session.looks import Looks
from initcli.session.perception import Perception
from initcli.session.result import SessionResult
from initcli.session.states import StateLog
from initcli.verify.registration import SubmapRegistration

__all__ = ["SessionParts", "assemble"]


@dataclass
class SessionParts:
    """What a session is made of, each part with one job."""

    options: MatchOptions  # the match step's options
    perception: Perception  # what the robot sees, and the detection log
    result: SessionResult  # what the session found
    states: StateLog  # the state it is in
    side: int  # the followed wall: +1 left, -1 right (exploration.wall_side)
    follow: WallFollowParams
    exploration: ActiveExploration
    escapes: Escapes
    looks: Looks
    claims: ClaimChecks
    registration: SubmapRegistration
    fine: FineStage
    # every storey matched maps onto itself turned: no reading tells a pose from its twin
    twins: str | None


def assemble(
    config: SessionConfig,
    site: Site,
    storey: str | None,
    driver: RobotDriver,
    log_path: Path | None,
    rng: np.random.Generator,
    meta_source: str,
) -> SessionParts:
    """The parts of a session of ``config`` on ``driver`` against ``site`` (``storey`` None: every
    storey), logging to ``log_path`` (None: no log file); ``rng`` for the particle filter."""
    options = match_options(config, storey)
    absent = bool(getattr(driver, "camera_absent", False))  # a live robot without a camera
    meta = Meta(
        driver.camera,
        driver.mount,
        depth_window=None if absent else driver.depth_window,
        source=meta_source,
        camera_absent=absent,
        lidar_mount=getattr(driver, "lidar_mount", None),
        storey=storey,
        settings=session_meta_settings(options, config.registration),
    )
    cmap, m, x, checks = (
        ClassMap(config.detector.classes),
        config.matching,
        config.exploration,
        config.verification,
    )
    tracker = site_tracker(site) if options.landmarks else None
    perception = Perception(meta, log_path, cmap, options, m.drift_window, config.lidar.log_every, tracker)
    follow = wall_follow_params(config)
    result = SessionResult(False, "", storey)
    states = StateLog(perception, result)
    view = CameraView(driver.camera, driver.mount, options.min_depth)
    return SessionParts(
        options=options,
        perception=perception,
        result=result,
        states=states,
        side=followed_side(config),
        follow=follow,
        exploration=ActiveExploration(config, site, follow),
        escapes=Escapes(x.loops, x.shuttles, x.frontier, x.laps, x.long_walls, follow, result),
        looks=Looks(x),
        claims=ClaimChecks(checks, site, perception, view, result, states.note),
        registration=SubmapRegistration(config.registration, site, storey, checks.scan_tolerance),
        fine=FineStage(config.fine_tuning, checks.min_fine_scan_fit, rng, follow),
        twins=twin_reason(site, storey),
    )
