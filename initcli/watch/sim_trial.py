"""A watch trial on the simulated robot (``bim-init eval --methods watch``): the robot starts with
its localiser right, explores as a session does (wall following), and after ``sim.kidnap`` m of
travel is carried to a random free place, its wheels unaware; a localiser stand-in keeps tracking
the old place by odometry, as AMCL does when it does not notice. The watch decides as it does live.

Before the kidnap (or all along, without one) the stand-in is right: the true pose with a little
noise, as a converged AMCL. After a recovery it takes the recovered pose: right again when that
pose is right, else carried on by odometry from the wrong one.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from bimtools.site.load import Site
from initcli.baselines.drive import WallFollowingExplorer
from initcli.config import SessionConfig
from initcli.config.building import choose_storey, world_storey
from initcli.core.geometry.se2 import Pose2D
from initcli.sim.build import build_sim
from initcli.sim.scenario import random_start
from initcli.storey.circulation import Circulation
from initcli.watch.monitor import Watcher
from initcli.watch.records import EventKind, WatchEvent

__all__ = ["AFTER_KIDNAP_M", "CONTROL_M", "WatchTrial", "watch_trial"]

AFTER_KIDNAP_M = 40.0  # m driven after the kidnap
CONTROL_M = 100.0  # m driven by a trial without a kidnap
STAND_IN_NOISE = (0.05, math.radians(1.0))  # m, rad: a converged localiser's own error
KIDNAP_APART_M = 5.0  # m: the robot is carried at least this far
KIDNAP_RNG_OFFSET = 4049  # the kidnap's and the stand-in's random numbers, apart from the simulator's
RIGHT_M, RIGHT_DEG = 0.5, 5.0  # a recovered pose this close is right (the stand-in tracks again)


@dataclass
class WatchTrial:
    storey: str
    start: Pose2D
    travel: float = 0.0  # m driven
    kidnap_m: float | None = None  # travel at the kidnap (None: none)
    control_m: float = 0.0  # m driven with the stand-in right (false alarms per km over these)
    false_alarms: int = 0  # lost while the stand-in was right
    lost_after_m: float | None = None  # m from the kidnap to the first lost after it
    recovered_after_m: float | None = None  # m from the kidnap to the first recovery after it
    recovery_error: tuple[float, float] | None = None  # m, degrees
    truth: Pose2D | None = None  # the true pose at the recovery (or the end)
    recovered: Pose2D | None = None
    events: list[WatchEvent] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def recovered_right(self) -> bool:
        e = self.recovery_error
        return e is not None and e[0] <= RIGHT_M and e[1] <= RIGHT_DEG


def _carry_to(
    site: Site, config: SessionConfig, storey: str, world: Site | None, here: Pose2D, rng: np.random.Generator
) -> Pose2D:
    """A random free place at least KIDNAP_APART_M from ``here``, where a robot fits."""
    circulation = Circulation.of(world_storey(site, world, storey))
    clearance = config.robot.radius + 0.3
    best = here
    for _ in range(200):
        best = random_start(circulation, rng, clearance)
        if best.distance_to(here) >= KIDNAP_APART_M:
            return best
    return best


def watch_trial(
    config: SessionConfig, site: Site, seed: int, start: Pose2D | None = None, world: Site | None = None
) -> WatchTrial:
    """One trial (module docstring): ``sim.kidnap`` m, then AFTER_KIDNAP_M m more; CONTROL_M m
    without a kidnap."""
    began = time.perf_counter()
    storey, _ = choose_storey(config, site)
    setup = build_sim(config, site, storey, seed, start, detect_features=False, world_site=world)
    driver = setup.driver
    explorer = WallFollowingExplorer(config)
    watcher = Watcher(
        site, storey, config.watch, replace(config.registration, enabled=True), config.verification
    )
    rng = np.random.default_rng(seed + KIDNAP_RNG_OFFSET)
    kidnap_at = config.sim.kidnap if config.sim.kidnap > 0 else None
    total = (kidnap_at + AFTER_KIDNAP_M) if kidnap_at is not None else CONTROL_M
    trial = WatchTrial(storey, setup.start)
    stale: Pose2D | None = None  # the stand-in's odom -> map while it tracks the wrong place
    frame = driver.start()
    steps = int(20 * total / max(config.robot.max_linear * 0.1, 1e-3))  # room for turns and waits
    for _ in range(steps):
        if driver.distance >= total:
            break
        if kidnap_at is not None and trial.kidnap_m is None and driver.distance >= kidnap_at:
            assert frame.truth is not None
            seen = _stand_in(frame.truth, rng)
            stale = seen * frame.odom.inverse()
            driver.robot.pose = _carry_to(site, config, storey, world, frame.truth, rng)
            trial.kidnap_m = watcher.travel
        v, w = explorer.command(frame)
        frame = driver.step(v, w)
        assert frame.truth is not None
        before = watcher.travel
        watcher.odom(frame.t, frame.odom)
        watcher.localiser(frame.t, _stand_in(frame.truth, rng) if stale is None else stale * frame.odom)
        if stale is None:
            trial.control_m += watcher.travel - before
        if frame.scan is None:
            continue
        for event in watcher.scan(
            frame.t, frame.scan.angles, np.asarray(frame.scan.ranges), frame.scan.range_max
        ):
            trial.events.append(event)
            stale = _on_event(trial, event, frame.truth, frame.odom, stale)
    trial.travel = watcher.travel
    trial.seconds = time.perf_counter() - began
    return trial


def _stand_in(truth: Pose2D, rng: np.random.Generator) -> Pose2D:
    m, rad = STAND_IN_NOISE
    return Pose2D(truth.x + rng.normal(0, m), truth.y + rng.normal(0, m), truth.yaw + rng.normal(0, rad))


def _on_event(
    trial: WatchTrial, event: WatchEvent, truth: Pose2D, odom: Pose2D, stale: Pose2D | None
) -> Pose2D | None:
    """Score ``event``; the stand-in's wrong odom -> map after it (None: it tracks the truth)."""
    kidnapped = trial.kidnap_m is not None
    if event.kind is EventKind.LOST:
        if not kidnapped or stale is None and trial.recovery_error is not None:
            trial.false_alarms += 1
        elif trial.lost_after_m is None:
            trial.lost_after_m = event.travel - (trial.kidnap_m or 0.0)
        return stale
    if event.kind is not EventKind.RECOVERED or event.pose is None:
        return stale
    if kidnapped and trial.recovery_error is None:
        trial.recovered_after_m = event.travel - (trial.kidnap_m or 0.0)
        trial.recovery_error = (event.pose.distance_to(truth), math.degrees(event.pose.yaw_error(truth)))
        trial.truth, trial.recovered = truth, event.pose
    right = (
        event.pose.distance_to(truth) <= RIGHT_M and math.degrees(event.pose.yaw_error(truth)) <= RIGHT_DEG
    )
    return None if right else event.pose * odom.inverse()
