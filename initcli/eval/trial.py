"""One evaluation trial: a site, a start, the methods asked for, all on the same simulated world.

Every method gets a simulator built from the same seed: the same clutter, workers, start pose
and sensor-noise model, driven by the same wall following. ``bim`` and ``bim+pf`` come from one
session (the ``bim`` result is the rectified pose at the unique match, §3.3.5; ``bim+pf``
continues with fine tuning), exactly as two separate runs with the same seed would; ``amcl`` and
``markers`` share one drive (:func:`initcli.baselines.drive.drive_attempts`), each ending where it
would have ended alone.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from bimtools.site.load import Site, load_site
from initcli.baselines.drive import BaselineAttempt, drive_attempts
from initcli.baselines.outcome import LocalisationOutcome
from initcli.config import SessionConfig, load_config
from initcli.config.building import choose_storey
from initcli.core.geometry.se2 import Pose2D
from initcli.eval.records import FailureRule, TrialRecord
from initcli.eval.scoring import score
from initcli.eval.sweep import Sweep, apply_sweep, sweep_label
from initcli.session.result import CANNOT_LEAVE, SessionResult
from initcli.session.simulated import sim_session
from initcli.sim.build import SimSetup, build_sim
from initcli.storey.circulation import NoFreeSpace

__all__ = ["TrialJob", "run_trial", "session_outcomes", "trial_seed"]


@dataclass(frozen=True)
class TrialJob:
    """Everything a worker process needs to run the methods of one (site, start, sweep value)."""

    site: str
    config_path: str  # the bim-init run site config
    site_dir: str  # the prepared site model (a bim-extract OUTDIR)
    start: int
    seed: int
    methods: tuple[str, ...]
    rule: FailureRule = field(default_factory=FailureRule)
    start_pose: tuple[float, float, float] | None = None  # x, y, yaw (radians); None: random
    sweep: Sweep | None = None
    sweep_value: float | None = None
    amcl: tuple[tuple[str, Any], ...] = ()
    markers: tuple[tuple[str, Any], ...] = ()
    world_dir: str = ""  # the prepared sim.world model ("": the robot lives in the BIM)
    reality: str | None = None  # a named reality replacing the site config's sim.reality


@lru_cache(maxsize=8)
def _site(site_dir: str) -> Site:
    return load_site(Path(site_dir))


@lru_cache(maxsize=8)
def _config(config_path: str, reality: str | None) -> SessionConfig:
    return load_config(Path(config_path), reality)


def _world(world_dir: str) -> Site | None:
    return _site(world_dir) if world_dir else None


def session_outcomes(result: SessionResult) -> dict[str, LocalisationOutcome]:
    """``bim`` (coarse + rectification, Eq. 17) and ``bim+pf`` (plus fine tuning, Eq. 18) of a session."""
    # The coarse-only method ends at the session's first claim (a failed fine stage may lead to
    # a second one, which only bim+pf gets to).
    claim = result.first_claim
    if claim is not None:
        bim = LocalisationOutcome(
            method="bim",
            localised=True,
            reason="unique match",
            pose=claim.rectified_pose,
            truth=claim.truth,
            distance_m=claim.distance_m,
            duration_s=result.duration_s,
            features=result.features_detected,
            wall_seconds=claim.wall_seconds,
        )
    else:
        bim = LocalisationOutcome(
            method="bim",
            localised=False,
            reason=result.reason,
            pose=None,
            truth=result.truth_pose,
            distance_m=result.distance_total_m,
            duration_s=result.duration_s,
            features=result.features_detected,
            wall_seconds=result.wall_seconds,
        )
    # The session's final pose is its claim, whether the filter's covariance fell below the
    # thresholds or its distance ran out first (the reason says which).
    fine = result.success and result.pose is not None
    bim.refused = result.reason == CANNOT_LEAVE
    bim_pf = LocalisationOutcome(
        method="bim+pf",
        localised=fine,
        reason=result.reason,
        pose=result.pose if fine else None,
        truth=result.truth_pose,
        distance_m=result.distance_total_m,
        duration_s=result.duration_s,
        features=result.features_detected,
        wall_seconds=result.wall_seconds,
        refused=bim.refused,
        covariance=result.covariance if fine else None,
    )
    return {"bim": bim, "bim+pf": bim_pf}


def _trial_config(job: TrialJob) -> SessionConfig:
    config = _config(job.config_path, job.reality)
    if job.sweep is not None and job.sweep_value is not None:
        return apply_sweep(config, job.sweep, job.sweep_value)
    return config


def run_trial(job: TrialJob) -> list[TrialRecord]:
    """Run the job's methods; one scored record per method. A storey the simulator can draw no
    start on (:class:`NoFreeSpace`) gives each method a refused record, not a traceback."""
    try:
        return _run_trial(job)
    except NoFreeSpace as e:
        sweep = sweep_label(job.sweep, job.sweep_value)
        outcomes = [
            LocalisationOutcome(m, False, str(e), None, None, 0.0, 0.0, refused=True) for m in job.methods
        ]
        return [
            score(
                o,
                job.rule,
                site=job.site,
                start=job.start,
                seed=job.seed,
                start_pose=(0.0, 0.0, 0.0),
                sweep=sweep,
            )
            for o in outcomes
        ]


def _run_trial(job: TrialJob) -> list[TrialRecord]:
    config = _trial_config(job)
    site = _site(job.site_dir)
    start = Pose2D(*job.start_pose) if job.start_pose is not None else None
    outcomes: list[LocalisationOutcome] = []
    start_pose: tuple[float, float, float] | None = None

    def baseline_sim() -> SimSetup:
        """The same world, start and noise as the session's, without the feature detector."""
        nonlocal start_pose
        simulated, _ = choose_storey(config, site)
        setup = build_sim(
            config, site, simulated, job.seed, start, detect_features=False, world_site=_world(job.world_dir)
        )
        start_pose = setup.start.as_tuple()
        return setup

    session_methods = [m for m in job.methods if m in ("bim", "bim+pf")]
    if session_methods:
        session_config = config
        if "bim+pf" not in session_methods:
            session_config = dataclasses.replace(
                config, fine_tuning=dataclasses.replace(config.fine_tuning, enabled=False)
            )
        built = sim_session(session_config, site, job.seed, start, world=_world(job.world_dir))
        start_pose = built.setup.start.as_tuple()
        result = built.session.run()
        both = session_outcomes(result)
        outcomes.extend(both[m] for m in session_methods)
    watch: list[TrialRecord] = []
    if "watch" in job.methods:
        from initcli.eval.watch_table import watch_record
        from initcli.watch.sim_trial import watch_trial

        trial = watch_trial(config, site, job.seed, start, _world(job.world_dir))
        start_pose = start_pose or trial.start.as_tuple()
        label = sweep_label(job.sweep, job.sweep_value)
        watch.append(
            watch_record(trial, job.rule, site=job.site, start=job.start, seed=job.seed, sweep=label)
        )
    attempts: list[BaselineAttempt] = []
    if any(m in job.methods for m in ("amcl", "markers")):
        # One drive for both: their wall following does not depend on what they sense.
        setup = baseline_sim()
        if "amcl" in job.methods:
            from initcli.baselines.amcl import AmclAttempt
            from initcli.core.filters.global_localisation import GlobalLocalisationParams

            params = dataclasses.replace(GlobalLocalisationParams(), **dict(job.amcl))
            attempts.append(AmclAttempt(config, site, setup, np.random.default_rng(job.seed + 1), params))
        if "markers" in job.methods:
            from initcli.baselines.markers import MarkerAttempt, MarkerParams

            params_m = dataclasses.replace(MarkerParams(), **dict(job.markers))
            attempts.append(MarkerAttempt(config, site, setup, np.random.default_rng(job.seed + 2), params_m))
        outcomes.extend(drive_attempts(config, setup.driver, attempts))
    assert start_pose is not None
    sweep = sweep_label(job.sweep, job.sweep_value)
    order = {m: i for i, m in enumerate(job.methods)}
    outcomes.sort(key=lambda o: order[o.method])
    records = [
        score(o, job.rule, site=job.site, start=job.start, seed=job.seed, start_pose=start_pose, sweep=sweep)
        for o in outcomes
    ] + watch
    return sorted(records, key=lambda r: order[r.method])


def trial_seed(base: int, start: int) -> int:
    return base + start
