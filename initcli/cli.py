"""``bim-init``: the thin typer app. Commands: ``match``, ``run``, ``eval``, ``detector``.

Exit codes: 0 unique match, 3 ambiguous (several hypotheses), 4 no consistent match, 2 bad input
(one line on stderr, never a traceback).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from bimtools.errors import InputError
from initcli.detector.cli import detector_app
from initcli.eval_cli import evaluate
from initcli.match import DEFAULT_POSE_METHOD, EXIT_BAD_INPUT, MatchOptions, run_match
from initcli.run_cli import run as run_session_command

app = typer.Typer(
    name="bim-init",
    help="Marker-free robot initialisation from BIM: match detected doors, lifts and stairs to the model.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)


@app.callback()
def _root() -> None:
    """Marker-free robot initialisation from BIM (paper §3.3): match detected doors, lifts and
    staircases to the same elements of the building model."""


def _fail(message: str) -> typer.Exit:
    typer.echo(f"bim-init: error: {' '.join(str(message).split())}", err=True)
    return typer.Exit(EXIT_BAD_INPUT)


@app.command()
def match(
    log: Annotated[Path, typer.Argument(metavar="LOG.jsonl", help="Detection log (JSON Lines, version 1).")],
    site: Annotated[
        Path, typer.Option("--site", metavar="SITE", help="bim-extract OUTDIR, or a features.csv (Table 1).")
    ],
    storey: Annotated[
        str,
        typer.Option("--storey", metavar="NAME|auto", help="Storey to match against; auto: every storey."),
    ] = "auto",
    alpha: Annotated[
        float, typer.Option("--alpha", metavar="M", help="Distance threshold of Eq. 7, metres.")
    ] = 0.5,
    beta: Annotated[
        float, typer.Option("--beta", metavar="DEG", help="Angle threshold of Eq. 9, degrees.")
    ] = 15.0,
    top: Annotated[int, typer.Option("--top", metavar="K", help="Hypotheses to show.")] = 5,
    json_out: Annotated[
        bool, typer.Option("--json", help="Print one JSON document instead of tables.")
    ] = False,
    plot: Annotated[
        Path | None, typer.Option("--plot", metavar="FILE.png", help="Draw the hypotheses on the floor plan.")
    ] = None,
    revisits: Annotated[
        bool,
        typer.Option(
            "--revisits/--no-revisits",
            help="Let a later detection match a BIM feature matched before (the robot came back); "
            "--no-revisits is the literal Algorithm 1.",
        ),
    ] = True,
    max_outliers: Annotated[
        int, typer.Option("--max-outliers", metavar="N", help="False or misclassified detections tolerated.")
    ] = 1,
    pose_method: Annotated[
        str,
        typer.Option(
            "--pose-method", metavar="paper|rigid", help="paper: Eq. 10-13; rigid: Kabsch on all matches."
        ),
    ] = DEFAULT_POSE_METHOD,
    d_thre: Annotated[
        float, typer.Option("--d-thre", metavar="M", help="Wall clearance of Eq. 17, metres.")
    ] = 0.5,
    min_sightings: Annotated[
        int, typer.Option("--min-sightings", metavar="K", help="Sightings that confirm a feature.")
    ] = 3,
    merge_radius: Annotated[
        float,
        typer.Option("--merge-radius", metavar="M", help="Same-class sightings closer than this merge."),
    ] = 1.0,
    score_threshold: Annotated[
        float, typer.Option("--score-threshold", metavar="S", help="Detections scoring lower are ignored.")
    ] = 0.5,
    drift_window: Annotated[
        float | None,
        typer.Option(
            "--drift-window",
            metavar="M",
            help="Match only the features confirmed in the last M metres of travel (odometry drift).",
        ),
    ] = None,
    skip_bad: Annotated[
        bool, typer.Option("--skip-bad", help="Skip malformed log lines (with a count) instead of failing.")
    ] = False,
) -> None:
    """Offline feature matching: confirmed features, ranked pose hypotheses and a verdict.

    Exit codes: 0 unique match, 3 several hypotheses, 4 no consistent match, 2 bad input.
    """
    options = MatchOptions(
        storey=None if storey.strip().lower() == "auto" else storey,
        alpha=alpha,
        beta_deg=beta,
        top=top,
        max_outliers=max_outliers,
        revisits=revisits,
        pose_method=pose_method,
        d_thre=d_thre,
        min_sightings=min_sightings,
        merge_radius=merge_radius,
        score_threshold=score_threshold,
        drift_window_m=drift_window,
        skip_bad=skip_bad,
    )
    try:
        report = run_match(log, site, options)
    except InputError as exc:
        raise _fail(str(exc)) from None

    for warning in report.warnings:
        typer.echo(f"bim-init: warning: {warning}", err=True)
    if json_out:
        from initcli.report import report_to_dict

        typer.echo(json.dumps(report_to_dict(report), indent=2))
    else:
        from initcli.report import print_report

        console = Console(width=None if sys.stdout.isatty() else 200, soft_wrap=False)
        print_report(report, console)
    if plot is not None:
        from initcli.tools.plot_hypotheses import plot_hypotheses

        try:
            plot_hypotheses(report, plot)
        except OSError as exc:
            raise _fail(f"{plot}: cannot write the plot: {exc.strerror or exc}") from None
    raise typer.Exit(report.exit_code)


app.command("run")(run_session_command)
app.command("eval")(evaluate)
app.add_typer(detector_app, name="detector")


def main() -> None:
    """Console-script entry point (``bim-init``)."""
    app()


if __name__ == "__main__":
    main()
