"""Planning and running the trials of an evaluation, in parallel processes or on a Ray cluster, resumable."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from bimtools.site.load import load_site
from initcli.config import SessionConfig, load_config
from initcli.config.building import choose_storey, input_paths, prepare_site, prepare_world
from initcli.core.geometry.se2 import Pose2D
from initcli.eval.config import EvalConfig, EvalSite
from initcli.eval.records import TrialKey, TrialRecord
from initcli.eval.sweep import Sweep, sweep_label
from initcli.eval.trial import TrialJob, run_trial, trial_seed
from initcli.executor import Executor, LocalExecutor, map_unordered
from initcli.sim.build import check_start

__all__ = ["PreparedSite", "check_start_poses", "plan_jobs", "prepare_sites", "run_jobs", "site_configs"]


@dataclass(frozen=True)
class PreparedSite:
    site: EvalSite
    site_dir: Path  # a bim-extract OUTDIR
    world_dir: Path | None = None  # the sim.world model, when the robot does not live in the BIM


def prepare_sites(config: EvalConfig, workdir: Path, only: Iterable[str] | None = None) -> list[PreparedSite]:
    """Load every site config and extract its IFC model once (into ``workdir/<site>``; sites on the
    same model, e.g. one per storey, share one extraction)."""
    wanted = set(only) if only is not None else None
    out = []
    extracted: dict[tuple[Path, str], Path] = {}
    worlds: dict[tuple[Path, str], Path | None] = {}
    for site in config.sites:
        if wanted is not None and site.name not in wanted:
            continue
        site_config = load_config(site.config)
        key = (site_config.site_path(), site_config.sim.world)
        if key not in extracted:
            prepared = prepare_site(site_config, workdir / site.name)
            world = prepare_world(site_config, workdir / site.name)
            extracted[key] = Path(prepared.root)
            worlds[key] = Path(world.root) if world is not None else None
        out.append(PreparedSite(site, extracted[key], worlds[key]))
    return out


def site_configs(config: EvalConfig, only: Iterable[str] | None = None) -> list[SessionConfig]:
    """The session config of every site the campaign runs (of ``only``, when given)."""
    wanted = set(only) if only is not None else None
    return [load_config(site.config) for site in config.sites if wanted is None or site.name in wanted]


def campaign_inputs(config: EvalConfig, only: Iterable[str] | None = None) -> list[Path]:
    """Every file and folder the campaign reads: the eval config, each site config and what it names."""
    paths = [config.source] if config.source is not None else []
    for site_config in site_configs(config, only):
        paths += input_paths(site_config)
    return paths


@dataclass(frozen=True)
class CampaignSize:
    """How many trials a campaign runs: sites x starts x methods x sweep values."""

    trials: int
    sites: int
    starts: int  # over all sites
    methods: int
    values: int  # sweep values (1 without a sweep)

    def __str__(self) -> str:
        sweep = f" x {self.values} sweep values" if self.values > 1 else ""
        return (
            f"{self.trials} trials ({self.starts} starts over {self.sites} site(s) x {self.methods} "
            f"method(s){sweep})"
        )


def trial_count(
    config: EvalConfig,
    methods: tuple[str, ...],
    starts: int | None = None,
    sweep: Sweep | None = None,
    only: Iterable[str] | None = None,
) -> CampaignSize:
    """The size of the campaign :func:`plan_jobs` would plan, from the config alone (before any
    site is prepared)."""
    wanted = set(only) if only is not None else None
    sites = [s for s in config.sites if wanted is None or s.name in wanted]
    n_starts = sum(_starts(s, starts) for s in sites)
    values = len(sweep.values) if sweep is not None else 1
    return CampaignSize(n_starts * len(methods) * values, len(sites), n_starts, len(methods), values)


def check_start_poses(config: EvalConfig, sites: list[PreparedSite]) -> None:
    """Every explicit start (``sites.N.start_poses``) is on a free cell of its storey's map; else
    one :class:`InputError` before any trial runs."""
    for index, site in enumerate(config.sites):
        prepared = next((p for p in sites if p.site is site), None)
        if prepared is None or not site.start_poses:
            continue
        session_config = load_config(site.config)
        model = load_site(prepared.site_dir)
        storey, _ = choose_storey(session_config, model)
        for k, pose in enumerate(site.start_poses):
            where = f"{config.source}: sites.{index}.start_poses.{k}"
            check_start(session_config, model.storeys[storey], Pose2D(*pose), where)


def plan_jobs(
    config: EvalConfig,
    sites: list[PreparedSite],
    methods: tuple[str, ...],
    starts: int | None = None,
    sweep: Sweep | None = None,
    done: set[TrialKey] | None = None,
    reality: str | None = None,
) -> list[TrialJob]:
    """One job per (sweep value, start, site) with the methods not finished yet.

    Starts are interleaved across sites so the progress bar's rate is representative early on.
    """
    done = done or set()
    values: list[float | None] = list(sweep.values) if sweep is not None else [None]
    jobs = []
    for value in values:
        label = sweep_label(sweep, value)
        n_max = max((_starts(p.site, starts) for p in sites), default=0)
        for k in range(n_max):
            for p in sites:
                if k >= _starts(p.site, starts):
                    continue
                todo = tuple(m for m in methods if TrialKey(p.site.name, k, m, *label) not in done)
                if not todo:
                    continue
                jobs.append(
                    TrialJob(
                        site=p.site.name,
                        config_path=str(p.site.config),
                        site_dir=str(p.site_dir),
                        start=k,
                        seed=trial_seed(config.seed, k),
                        methods=todo,
                        rule=config.rule,
                        start_pose=p.site.start_poses[k] if p.site.start_poses else None,
                        sweep=sweep,
                        sweep_value=value,
                        amcl=tuple(sorted(config.amcl.items())),
                        markers=tuple(sorted(config.markers.items())),
                        world_dir=str(p.world_dir) if p.world_dir is not None else "",
                        reality=reality,
                    )
                )
    return jobs


def _starts(site: EvalSite, override: int | None) -> int:
    if site.start_poses:
        return len(site.start_poses) if override is None else min(override, len(site.start_poses))
    return override if override is not None else site.starts


def run_jobs(
    jobs: list[TrialJob],
    workers: int,
    on_records: Callable[[list[TrialRecord]], None],
    executor: Executor | None = None,
) -> None:
    """Run the jobs on ``executor`` (default: ``workers`` local processes, 1: in this process);
    report each job's records as it ends. Ctrl-C stops it; the records reported so far stand."""
    runner = executor or LocalExecutor(workers)
    try:
        for _, records in map_unordered(runner, [(run_trial, job) for job in jobs]):
            on_records(records)
    finally:
        if executor is None:
            runner.close()
