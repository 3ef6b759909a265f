"""``bim-init eval``: many sessions and baselines on simulated starts, scored like the paper's §4."""

from __future__ import annotations

import shlex
import shutil
import sys
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table
from rich.text import Text

from bimkit.atomic import claim
from bimkit.cli import EXIT_INTERRUPTED, fail, number_option
from bimkit.errors import InputError
from bimkit.outputs import OutputFolder, check_outputs
from initcli.cli import PROG, check_reality
from initcli.eval.campaign import (
    campaign_inputs,
    check_start_poses,
    plan_jobs,
    prepare_sites,
    run_jobs,
    site_configs,
    trial_count,
)
from initcli.eval.config import EvalConfig, load_eval_config, parse_methods
from initcli.eval.consistency import consistency_rows
from initcli.eval.records import TrialRecord
from initcli.eval.report import RunStats, write_report
from initcli.eval.results_file import ResultsWriter, read_results
from initcli.eval.sweep import check_sweep, parse_sweep
from initcli.eval.tables import NONE, table2, table3
from initcli.eval.trial import TrialJob
from initcli.eval.watch_table import watch_rows
from initcli.executor import Executor, default_workers, make_executor

__all__ = ["EVAL_MARKERS", "EXIT_INTERRUPTED", "evaluate"]

EVAL_MARKERS = ("results.jsonl", "table.md")  # an --out folder holding one was written by bim-init eval
EVAL_WRITES = ("results.jsonl", "table.csv", "table.md", "fig9.png", "fig12_*.png", "sweep_*.png", ".sites")
MAX_TRIALS = 20_000  # a campaign of more trials (about 3 hours on 2 cores) runs only with --yes


def _rich_table(title: str, header: list[str], rows: list[list[str]], width: int = 200) -> Table:
    """The markdown table for a terminal ``width`` columns wide: each ``(paper)`` column folded into
    the one before it as ``ours (paper)``; the columns that do not fit left out, from the right (the
    caption says so: every column is in table.md)."""
    keep = [i for i, h in enumerate(header) if h != "(paper)"]
    cells = []
    for row in rows:
        line = []
        for i in keep:
            paired = i + 1 < len(header) and header[i + 1] == "(paper)"
            line.append(f"{row[i]} [dim]({row[i + 1]})[/dim]" if paired and row[i + 1] != NONE else row[i])
        cells.append(line)
    shown, used = 0, 1
    for k, i in enumerate(keep):
        plain = [Text.from_markup(c[k]).plain for c in cells]
        need = max([len(w) for w in header[i].split()] + [len(p) for p in plain]) + 3
        if shown >= 2 and used + need > width:
            break
        shown, used = shown + 1, used + need
    left_out = len(keep) - shown
    caption = f"{left_out} more column(s) in table.md" if left_out else None
    table = Table(title=title, title_justify="left", caption=caption, caption_justify="left")
    for n, i in enumerate(keep[:shown]):
        table.add_column(header[i], justify="left" if n < 2 else "right")
    for line in cells:
        table.add_row(*line[:shown])
    return table


# The options of eval that take more than a line (typer reads these Annotated types).
_Config = Annotated[
    Path | None,
    typer.Option(
        "--config",
        metavar="eval.yaml",
        help="Eval config [default: sample_models/eval.yaml of the source tree].",
    ),
]
_Starts = Annotated[
    int | None,
    typer.Option(
        "--starts",
        metavar="N",
        help="Starts per site, 1-100000 (overrides the config).",
        callback=number_option(PROG, minimum=1, maximum=100000),
    ),
]
_Methods = Annotated[
    str | None,
    typer.Option("--methods", metavar="M,...", help="Some of bim, bim+pf, amcl, markers [default: config]."),
]
_Workers = Annotated[
    int | None,
    typer.Option(
        "--workers",
        metavar="W",
        help="Parallel processes, 1-1024 [default: all cores].",
        callback=number_option(PROG, minimum=1, maximum=1024),
    ),
]
_Resume = Annotated[
    bool, typer.Option("--resume", help="Keep DIR/results.jsonl and run only the trials it lacks.")
]
_Force = Annotated[
    bool,
    typer.Option(
        "--force",
        help="Write into an --out folder that holds other files than an eval's (they are kept).",
    ),
]
_Yes = Annotated[bool, typer.Option("--yes", help=f"Run a campaign of more than {MAX_TRIALS} trials.")]
_Sweep = Annotated[
    str | None,
    typer.Option(
        "--sweep",
        metavar="KEY=V1,V2,...",
        help="Vary one parameter (miss_rate, false_positives, depth_noise, odometry_drift, clutter, people, "
        "alpha, beta, or a dotted site-config path), the rest fixed.",
    ),
]
_Sites = Annotated[
    str | None, typer.Option("--sites", metavar="NAME,...", help="Only these sites of the config.")
]
_Reality = Annotated[
    str | None,
    typer.Option(
        "--reality",
        metavar="ideal|construction",
        help="Run every site in this named reality (sim.reality; keys a site config sets win).",
    ),
]
_Executor = Annotated[
    str,
    typer.Option("--executor", metavar="local|ray", help="Where the trials run: local processes or Ray."),
]
_Address = Annotated[
    str | None,
    typer.Option(
        "--address", metavar="ADDR", help="Ray cluster (auto, ray://host:10001) [default: a local one]."
    ),
]


def evaluate(
    config: _Config = None,
    starts: _Starts = None,
    methods: _Methods = None,
    workers: _Workers = None,
    out: Annotated[Path, typer.Option("--out", metavar="DIR", help="Output folder.")] = Path("eval_results"),
    resume: _Resume = False,
    force: _Force = False,
    sweep: _Sweep = None,
    sites: _Sites = None,
    reality: _Reality = None,
    executor: _Executor = "local",
    address: _Address = None,
    yes: _Yes = False,
) -> None:
    """Reproduce the paper's Tables 2 and 3: success, distance and error of every method over many starts."""
    console = Console(stderr=False)
    err = Console(stderr=True)
    existed = out.exists()
    try:
        eval_config = load_eval_config(config)
        chosen = parse_methods(methods) if methods else eval_config.methods
        the_sweep = parse_sweep(sweep) if sweep else None
        check_reality(reality)
        only = _only_sites(sites, eval_config)
        if the_sweep is not None:
            check_sweep(the_sweep, site_configs(eval_config, only))
        check_outputs(
            campaign_inputs(eval_config, only), [OutputFolder(out, "--out", EVAL_MARKERS, EVAL_WRITES)], force
        )
        size = trial_count(eval_config, chosen, starts, the_sweep, only)
        if size.trials > MAX_TRIALS and not yes:
            raise InputError(
                f"{size}: more than {MAX_TRIALS} trials (hours of work); pass --yes to run them, "
                "or fewer --starts, --methods or --sites"
            )
        results_path = out / "results.jsonl"
        previous: list[TrialRecord] = read_results(results_path) if resume and results_path.exists() else []
        with err.status("preparing site models (extracting IFC)..."):
            prepared = prepare_sites(eval_config, out / ".sites", only)
            check_start_poses(eval_config, prepared)
        runner = make_executor(executor, workers, address)
    except InputError as exc:
        if not existed:  # nothing left behind: the site models extracted so far go too
            shutil.rmtree(out, ignore_errors=True)
        fail(PROG, exc)
    n_workers = runner.slots if executor != "local" else workers or default_workers()
    done = {r.key for r in previous}
    jobs = plan_jobs(eval_config, prepared, chosen, starts, the_sweep, done, reality)
    total = sum(len(j.methods) for j in jobs)
    if previous:
        err.print(f"resuming: {len(previous)} trials in {results_path} kept, {total} to run")
    records = list(previous)
    started = time.perf_counter()
    environments = {s.name: s.paper for s in eval_config.sites}
    command = (
        "bim-init " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:] else "bim-init eval"
    )
    try:
        ran = _run_trials(jobs, total, n_workers, runner, results_path, resume, records, err)
    except KeyboardInterrupt:
        runner.close(cancel=True)
        if out.is_dir():
            claim(out, EVAL_WRITES)
        err.print(
            f"interrupted: {len(records)} trials saved in {results_path}; rerun with --resume to continue"
        )
        raise typer.Exit(EXIT_INTERRUPTED) from None
    finally:
        runner.close()
    stats = RunStats(ran, time.perf_counter() - started, n_workers)
    summaries = write_report(out, records, environments, eval_config.rule, stats, command)
    claim(out, EVAL_WRITES)
    summaries = [s for s in summaries if s.method != "watch"]  # its own table
    header, rows = table2(summaries, environments)
    if rows:
        console.print(
            _rich_table(
                "Table 2: BIM-based initialisation per site, ours (paper)", header, rows, console.width
            )
        )
    header, rows = table3(summaries, environments, long_names=False)
    if rows:
        console.print(_rich_table("Table 3: methods compared, ours (paper)", header, rows, console.width))
    header, rows = consistency_rows(records)
    if rows:
        console.print(
            _rich_table("Pose and covariance (NEES, the 99 % ellipse)", header, rows, console.width)
        )
    header, rows = watch_rows(records)
    if rows:
        console.print(_rich_table("Lost and found (bim-init watch, sim.kidnap)", header, rows, console.width))
    if ran:
        console.print(
            f"{ran} trials in {stats.seconds:.0f} s on {n_workers} worker(s): "
            f"{stats.per_minute:.1f} trials/min"
        )
    console.print(f"wrote {out}/results.jsonl, table.csv, table.md and plots")


def _only_sites(sites: str | None, eval_config: EvalConfig) -> list[str] | None:
    """The sites ``--sites`` names (None: every site of the config); InputError for one not in it."""
    only = sites.replace(",", " ").split() if sites else None
    if only:
        unknown = [s for s in only if s not in {x.name for x in eval_config.sites}]
        if unknown:
            names = ", ".join(x.name for x in eval_config.sites)
            raise InputError(f"--sites: no site {unknown[0]!r} in the config (sites: {names})")
    return only


def _run_trials(
    jobs: list[TrialJob],
    total: int,
    n_workers: int,
    runner: Executor,
    results_path: Path,
    resume: bool,
    records: list[TrialRecord],
    err: Console,
) -> int:
    """Run the trials with a progress bar on ``err``, each record written to ``results_path`` (appended
    with ``resume``) as it comes and appended to ``records``; the number of trials run."""
    ran = 0
    with (
        ResultsWriter(results_path, append=resume) as writer,
        Progress(
            TextColumn("[bold]eval[/bold]"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("trials"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            TextColumn("{task.fields[last]}"),
            console=err,
        ) as progress,
    ):
        task = progress.add_task("trials", total=total, last="")

        def finished(batch: list[TrialRecord]) -> None:
            nonlocal ran
            for record in batch:
                writer.write(record)
                records.append(record)
            ran += len(batch)
            last = batch[-1]
            progress.update(task, advance=len(batch), last=f"{last.site} #{last.start}")

        run_jobs(jobs, n_workers, finished, runner)
    return ran
