"""``bim-init survey``: where on a floor the robot can be put down and initialise, from the BIM alone."""

from __future__ import annotations

import json
from functools import partial
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

from bimkit.atomic import claim, write_text_atomic
from bimkit.cli import EXIT_INTERRUPTED, fail, number_option
from bimkit.errors import InputError
from bimkit.outputs import OutputFolder, check_outputs, removed_on_storage_error
from bimtools.site.load import Site, load_site
from bimtools.site.names import storey_slugs
from initcli.cli import PROG, check_reality
from initcli.config import SessionConfig, camera_of, followed_side, load_config
from initcli.config.load import parse_config
from initcli.core.features.visibility import CameraModel
from initcli.executor import Executor, make_executor
from initcli.match.pipeline import site_class_map
from initcli.survey.landmarks import Landmark, suggest_landmarks
from initcli.survey.lidar import LidarModel
from initcli.survey.plan import StoreyPlan, SurveyParams, plan_storey
from initcli.survey.run import StoreySurvey, survey_storey
from initcli.survey.summary import summarise
from initcli.survey.uniqueness import UniquenessParams

__all__ = ["EXIT_INTERRUPTED", "SURVEY_MARKERS", "SURVEY_VERSION", "survey", "survey_params"]

SURVEY_VERSION = 1
SURVEY_MARKERS = ("survey.json",)  # an --out folder holding one was written by bim-init survey
SURVEY_WRITES = ("survey.json", "survey_*.png")  # what it writes there
MAX_STARTS = 100_000  # a survey of more starts (positions x headings) runs only with --yes


def survey_params(config: SessionConfig, spacing: float, headings: int) -> SurveyParams:
    """The survey's settings from a session config (camera, matching, exploration, limits, the lidar
    and its registration)."""
    camera, mount = camera_of(config)
    m = config.matching
    return SurveyParams(
        spacing=spacing,
        headings=headings,
        limit_m=config.limits.max_distance,
        initial_look=config.exploration.initial_look,
        wall_distance=config.exploration.wall_distance,
        side=followed_side(config),
        min_sightings=m.min_sightings,
        scan_tolerance=config.verification.scan_tolerance,
        camera_on=config.robot.rosbridge.camera != "absent" and config.sim.miss_rate < 1.0,
        registration=config.registration,
        lidar=LidarModel(config.lidar.beams, config.lidar.fov, config.lidar.max_range),
        camera=CameraModel(
            camera, mount, max_range=config.camera.range, max_view_angle_deg=config.camera.max_view_angle
        ),
        matching=UniquenessParams(
            alpha=m.alpha,
            beta_deg=m.beta,
            max_outliers=m.max_outliers + as_built_outliers(config),
            min_claim=config.verification.min_claim_inliers if config.verification.enabled else 0,
        ),
    )


def as_built_outliers(config: SessionConfig) -> int:
    """Outliers the site as built adds to a match: one where the robot meets doors the model lacks
    (``sim.as_built.extra_doors``) or a detector that takes a panel for a door every time
    (``sim.detector.persistent_phantoms``). Each costs the session's match an outlier, and a rival
    place that needs one more outlier then passes as well: on a storey of repeating rooms the
    session drives on. The survey predicts it by allowing the matching one outlier more."""
    sim = config.sim
    return 1 if sim.as_built.extra_doors > 0 or sim.detector.persistent_phantoms > 0 else 0


def _session(config: Path | None, reality: str | None, site: Path) -> SessionConfig:
    """The run config the survey of ``site`` takes its settings from (none: the defaults), in
    ``reality`` (none: the config's)."""
    check_reality(reality)
    if config is not None:
        return load_config(config, reality)
    if reality is None:
        return SessionConfig()
    return parse_config({"site": {"path": str(site)}, "sim": {"reality": reality}})


# The options of survey that take more than a line (typer reads these Annotated types).
_Config = Annotated[
    Path | None,
    typer.Option(
        "--config", metavar="site.yaml", help="Camera, matching and exploration settings of a run config."
    ),
]
_Spacing = Annotated[
    float,
    typer.Option(
        "--spacing",
        metavar="M",
        help="Metres between start positions, [0.1, 100].",
        callback=number_option(PROG, minimum=0.1, maximum=100),
    ),
]
_Headings = Annotated[
    int,
    typer.Option(
        "--headings",
        metavar="N",
        help="Start headings per position, 1-360.",
        callback=number_option(PROG, minimum=1, maximum=360),
    ),
]
_Landmarks = Annotated[
    int,
    typer.Option(
        "--landmarks",
        metavar="N",
        help="Extra landmarks to suggest (0-2).",
        callback=number_option(PROG, minimum=0, maximum=2),
    ),
]
_Executor = Annotated[
    str,
    typer.Option(
        "--executor",
        metavar="local|ray",
        help="Where the matching and the lidar runs: local processes or Ray.",
    ),
]
_Workers = Annotated[
    int | None,
    typer.Option(
        "--workers",
        metavar="W",
        help="Local processes, 1-1024 [default: all cores].",
        callback=number_option(PROG, minimum=1, maximum=1024),
    ),
]
_Address = Annotated[
    str | None, typer.Option("--address", metavar="ADDR", help="Ray cluster (auto, ray://host:10001).")
]
_Force = Annotated[
    bool,
    typer.Option("--force", help="Write into an --out folder holding other files than a survey's (kept)."),
]
_Reality = Annotated[
    str | None,
    typer.Option(
        "--reality",
        metavar="ideal|construction",
        help="Survey the site in this named reality (sim.reality; keys the --config sets win): as"
        " built, one door the model lacks may join a match [default: the config's].",
    ),
]
_Yes = Annotated[bool, typer.Option("--yes", help=f"Run a survey of more than {MAX_STARTS} starts.")]


def survey(
    site: Annotated[Path, typer.Argument(metavar="SITE", help="A bim-extract output folder.")],
    storey: Annotated[str, typer.Option("--storey", metavar="NAME|all", help="Storey to survey.")] = "all",
    out: Annotated[Path, typer.Option("--out", metavar="DIR", help="Output folder.")] = Path("survey"),
    config: _Config = None,
    spacing: _Spacing = 1.0,
    headings: _Headings = 4,
    landmarks: _Landmarks = 2,
    executor: _Executor = "local",
    workers: _Workers = None,
    address: _Address = None,
    force: _Force = False,
    yes: _Yes = False,
    reality: _Reality = None,
) -> None:
    """Map the distance to a unique match over a floor from its features and walls alone (no noise):
    sampled starts look round, follow the wall and match until one hypothesis is left."""
    console = Console()
    err = Console(stderr=True)
    try:
        check_outputs([site, config], [OutputFolder(out, "--out", SURVEY_MARKERS, SURVEY_WRITES)], force)
        model = load_site(site)
        session = _session(config, reality, site)
        params = survey_params(session, spacing, headings)
        names = list(model.storeys) if storey == "all" else [model.storey(storey).name]
        cmap = site_class_map(model)
        plans: dict[str, StoreyPlan] = {}
        for name in names:
            try:
                plans[name] = plan_storey(model.storeys[name], params, cmap)
            except ValueError as exc:
                err.print(f"storey {name}: skipped ({exc})")
        if not plans:  # nothing to survey is no survey: refused, not written empty
            raise InputError(f"{site}: no storey with an occupancy map to survey ({', '.join(names)})")
        n_starts = sum(len(p.starts) for p in plans.values())
        if n_starts > MAX_STARTS and not yes:
            raise InputError(
                f"{n_starts} starts ({n_starts // headings} positions {spacing:g} m apart x {headings} "
                f"headings over {len(plans)} storey(s)): more than {MAX_STARTS} (hours of work); pass --yes "
                "to run them, or a larger --spacing or fewer --headings"
            )
        runner = make_executor(executor, workers, address)
    except InputError as exc:
        fail(PROG, exc)
    storeys: list[dict[str, object]] = []
    suggested: list[str] = []
    report: dict[str, object] = {
        "version": SURVEY_VERSION,
        "site": str(site),
        "limit_m": params.limit_m,
        "reality": session.sim.reality,
        "max_outliers": params.matching.max_outliers,
        "storeys": storeys,
    }
    stems = _stems(model)
    table = _survey_table()
    with removed_on_storage_error(out):  # a full disk mid-way: none of this run's maps left
        try:
            with Progress(
                TextColumn("[bold]survey[/bold] {task.fields[storey]}"),
                BarColumn(),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                console=err,
            ) as progress:
                for name, plan in plans.items():
                    stem = stems[name]
                    entry, chosen = _survey_one(name, plan, params, runner, landmarks, progress, out, stem)
                    storeys.append(entry)
                    table.add_row(*_table_row(name, entry))
                    line = _landmarks_line(name, chosen)
                    if line:
                        suggested.append(line)
        except KeyboardInterrupt:
            runner.close(cancel=True)
            if out.is_dir():
                claim(out, SURVEY_WRITES)
            err.print("interrupted: nothing written for the unfinished storey")
            raise typer.Exit(EXIT_INTERRUPTED) from None
        finally:
            runner.close()
        out.mkdir(parents=True, exist_ok=True)
        write_text_atomic(out / "survey.json", json.dumps(report, indent=2) + "\n")
        claim(out, SURVEY_WRITES)
    console.print(table)
    for line in suggested:
        console.print(line, markup=False, highlight=False)
    for entry in storeys:
        line = _lidar_twin_line(entry)
        if line:
            console.print(line)
    console.print(f"wrote {out}/survey.json and the maps")


def _survey_table() -> Table:
    """The terminal table, one row per storey; it fits 80 columns: the headers are stacked short
    words and every cell wraps (a long storey name over lines), none is cut with an ellipsis."""
    table = Table(title="Survey: starts unique within 5, 10, 20 m", title_justify="left")
    for column in (
        "storey",
        "starts",
        "area\nm2",
        "<=5 m",
        "<=10 m",
        "<=20 m",
        "median\nm",
        "never\nunique\nm2",
    ):
        table.add_column(column, justify="left" if column == "storey" else "right", overflow="fold")
    return table


def _survey_one(
    name: str,
    plan: StoreyPlan,
    params: SurveyParams,
    runner: Executor,
    landmarks: int,
    progress: Progress,
    out: Path,
    stem: str,
) -> tuple[dict[str, object], list[Landmark]]:
    """Survey one storey (and suggest ``landmarks`` extra landmarks), draw its map into ``out``; its
    entry of survey.json and the landmarks chosen."""
    from initcli.survey.plots import survey_png

    task = progress.add_task("starts", total=len(plan.starts), storey=name)
    result, views = survey_storey(plan, params, runner, partial(progress.advance, task))
    entry = summarise(result)
    chosen: list[Landmark] = []
    improved: StoreySurvey | None = None
    if landmarks:
        n_cand = landmarks * params.landmark_candidates
        task_l = progress.add_task("landmarks", total=n_cand, storey=f"{name} landmarks")
        advance = partial(progress.advance, task_l)
        chosen, improved = suggest_landmarks(result, views, landmarks, runner, advance)
        progress.update(task_l, completed=n_cand)
        entry["landmarks"] = [
            {
                "x": round(lm.x, 3),
                "y": round(lm.y, 3),
                "norm_x": round(lm.norm_x, 4),
                "norm_y": round(lm.norm_y, 4),
                "category": lm.cls,
                "mean_distance_m": round(lm.mean_distance_m, 2),
            }
            for lm in chosen
        ]
        entry["with_landmarks"] = summarise(improved)
    out.mkdir(parents=True, exist_ok=True)
    survey_png(out / f"survey_{stem}.png", result, improved, chosen)
    entry["map"] = f"survey_{stem}.png"
    return entry, chosen


def _stems(model: Site) -> dict[str, str]:
    """Each storey's ``<slug>`` of ``survey_<slug>.png``: the one of its ``map_<slug>.yaml`` where
    site.json records that (so a site written by an older rule keeps its names), else the site's
    storeys slugged together by the one rule (:mod:`bimtools.site.names`), as bim-extract does."""
    slugs = dict(zip(model.storeys, storey_slugs(model.storeys), strict=True))
    recorded = {
        info.name: info.map_yaml[4:-5]
        for info in (model.manifest.storeys if model.manifest is not None else [])
        if info.map_yaml and info.map_yaml.startswith("map_") and info.map_yaml.endswith(".yaml")
    }
    stems: dict[str, str] = {}
    for name, slug in slugs.items():
        stem = recorded.get(name) or slug
        if stem in stems.values():  # a hand-edited site.json naming one map twice
            stem = slug
        stems[name] = stem
    return stems


def _lidar_twin_line(entry: dict[str, object]) -> str | None:
    """What the camera off means on a storey with lidar twins in its start region, or None."""
    share = float(entry["lidar_twin_start_share"])  # type: ignore[arg-type]
    if share <= 0:
        return None
    twins = [t for t in entry["lidar_twins"] if t["start_region"]]  # type: ignore[attr-defined]
    where = "; ".join(
        f"({t['x']:.1f}, {t['y']:.1f}) like ({t['twin_x']:.1f}, {t['twin_y']:.1f})"
        f" turned {t['turn_deg']:.0f} deg"
        for t in twins[:3]
    )
    more = f" and {len(twins) - 3} more" if len(twins) > 3 else ""
    return (
        f"{entry['storey']}: {100 * share:.0f} % of the start area has a lidar twin with its doors shut "
        f"({where}{more}): with the camera off a start there cannot be told from its twin"
    )


def _table_row(name: str, entry: dict[str, object]) -> list[str | Text]:
    """A storey's row of the terminal table (its name as plain text: no markup read in it)."""
    shares = entry["unique_within"]
    median = entry["median_distance_m"]
    return [
        Text(name),
        str(entry["samples"]),
        f"{entry['area_m2']:.0f}",
        *(f"{100 * shares[k]:.0f} %" for k in ("5m", "10m", "20m")),  # type: ignore[index]
        "never" if median is None else f"{median:.1f}",
        f"{entry['never_unique_area_m2']:.0f}",
    ]


def _landmarks_line(name: str, chosen: list[Landmark]) -> str | None:
    """Where the suggested landmarks of a storey go (below the table: coordinates would not fit
    a column at 80 characters), or None without them."""
    if not chosen:
        return None
    places = ", ".join(f"({lm.x:.1f}, {lm.y:.1f})" for lm in chosen)
    return f"{name}: landmarks suggested at {places} (m, BIM frame)"
