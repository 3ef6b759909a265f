"""A session on a live robot behind a rosbridge server (``robot.driver: rosbridge``): its state goes
to ``/bim_init/state`` and its hypotheses to ``/bim_init/hypotheses`` while it runs, the result to
``/initialpose`` (Nav2), carried forward by odometry and confirmed (:mod:`initcli.ros.delivery`).

Everything is on the robot's clock (its odometry's stamps). A run that fails or is interrupted
once the robot is driving keeps what it saw: the session log and a ``summary.json`` saying why it
stopped are put in ``--out`` (atomically) before the error goes on; the robot's last command is a
zero Twist.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bimkit.atomic import staged_directory
from bimkit.errors import InputError
from initcli.config import SessionConfig, camera_of, config_to_dict
from initcli.config.building import choose_storey, prepare_site
from initcli.core.filters.particle_filter import FilterNoise
from initcli.core.geometry.se2 import Pose2D
from initcli.ros.delivery import CarriedPose, deliver_initial_pose, pose_record
from initcli.ros.live_camera import live_camera
from initcli.ros.rosbridge import RosbridgeLink
from initcli.ros.rosbridge_driver import RosbridgeDriver
from initcli.session.outputs import summary_document, write_summary
from initcli.session.result import MatchStep, SessionResult
from initcli.session.runner import Observer, Session
from initcli.session.simulated import RUN_MARKERS, SESSION_RNG_OFFSET

__all__ = ["run_live", "stopped_reason"]


def stopped_reason(exc: BaseException) -> str:
    """Why a live run stopped, for ``summary.json``'s ``reason``."""
    if isinstance(exc, KeyboardInterrupt):
        return "stopped: interrupted (Ctrl-C or SIGTERM)"
    return f"stopped: {exc or type(exc).__name__}"


def _clock(driver: RosbridgeDriver) -> dict[str, Any]:
    return {
        "origin_stamp": driver.clock_origin,
        "source": "this machine's clock (odometry without stamps)"
        if driver.wall_clock
        else "odometry header.stamp",
        "stamps": "ros1 (secs, nsecs)" if driver.ros1 else "ros2 (sec, nanosec)",
    }


def _deliver(config: SessionConfig, result: SessionResult, driver: RosbridgeDriver) -> dict[str, Any]:
    """Send the claim's pose carried to the newest odometry; the summary's ``claim``,
    ``published`` and ``delivery``."""
    assert result.pose is not None and result.transform is not None
    claim_stamp = driver.frame_stamp  # the session ends on the frame of its claim
    carried = CarriedPose(result.transform, result.covariance, claim_stamp, driver.odometry, FilterNoise())
    report = deliver_initial_pose(driver.link, carried, config.nav2, driver.ros1)
    stamp, pose, cov = carried.sent or carried.now()  # the last pose sent
    return {
        "claim": pose_record(claim_stamp, result.pose, result.covariance),
        "published": pose_record(stamp, pose, cov),
        "delivery": report,
    }


def run_live(
    config: SessionConfig,
    out: Path,
    seed: int,
    view: Observer | None = None,
    warn: Callable[[str], None] = lambda line: None,
) -> dict:
    """``robot.driver: rosbridge``: the session on the real robot behind a rosbridge server (see the
    module docstring); returns ``summary.json``'s document. The camera comes from the robot's
    CameraInfo and ``/tf_static`` where it sends them (``warn`` gets a line where the site config's
    values are used instead or disagree); a robot without one (``robot.rosbridge.camera``) runs on
    the lidar alone: no detections or depth subscribed, the log's meta and ``summary.json`` say
    ``camera_absent``. The laser's mount comes from ``/tf_static``. An error once the session runs
    is raised again after ``--out`` holds its log and summary."""
    r = config.robot
    stopped: BaseException | None = None
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
            camera_topics=False,  # the detections and depth only once the robot is known to have a camera
            warn=warn,
        )
        driver.wait_odometry(r.rosbridge.camera_wait)
        seen = live_camera(link, r.rosbridge, camera, mount, driver.laser_base, driver.static)
        driver.camera, driver.mount = seen.camera, seen.mount
        driver.camera_absent = seen.absent
        for line in seen.warnings:
            warn(line)
        if not seen.absent:
            driver.listen_camera()
        driver.wait_laser(r.rosbridge.camera_wait)  # the laser's mount, for the log's meta
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
        extra: dict[str, Any] = {}
        result = session.result
        try:
            try:
                result = session.run()
            finally:
                driver.stop()  # the robot's last command: a zero Twist
            if result.success:
                extra = _deliver(config, result, driver)
                driver.publish_state("initialised")
        except (Exception, KeyboardInterrupt) as exc:  # kept: the log and why it stopped
            stopped = exc
            if not result.success or not extra:
                result.success = False
                result.reason = stopped_reason(exc)
        doc = summary_document(
            result,
            simulated=False,
            extra={
                "clock": _clock(driver),
                "camera_absent": seen.absent,
                "camera": seen.record(),
                "lidar": driver.lidar_record(),
                **extra,
                "config": config_to_dict(config),
            },
        )
        write_summary(stage / "summary.json", doc)
        driver.close()
    if isinstance(stopped, InputError):
        raise InputError(f"{stopped} (what the run saw is in {out}: session.jsonl, summary.json)") from None
    if stopped is not None:
        raise stopped
    return doc
