"""``bim-init match``: a detection log against the feature table, and the console tables of the result.

Exit codes: 0 unique match, 3 ambiguous (several hypotheses), 4 no consistent match, 2 bad input
(one line on stderr, never a traceback).
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from bimkit.cli import error_line
from bimkit.errors import InputError
from bimkit.outputs import OutputFile, check_outputs
from initcli.cli import PROG
from initcli.cli.progress import message_progress
from initcli.core.geometry import Pose2D
from initcli.core.verification import TRACK_HYPOTHESES, Verification
from initcli.io.match_result import report_to_dict
from initcli.match.pipeline import EXIT_BAD_INPUT, MatchOptions, MatchReport, run_match
from initcli.match.verify import check_hypotheses
from initcli.ros.convert import log_or_bag


def _fail(message: object) -> typer.Exit:
    typer.echo(error_line(PROG, message), err=True)
    return typer.Exit(EXIT_BAD_INPUT)


def _fmt_pose(p: Pose2D | None) -> str:
    if p is None:
        return "-"
    return f"{p.x:8.3f} {p.y:8.3f} {math.degrees(p.yaw):7.1f}°"


def _fmt_checks(check: Verification | None) -> str:
    """A hypothesis's verification in a few words: passed or not, missed predictions, scan fit."""
    if check is None:
        return "-"
    fit = "" if check.scan_fit is None else f", fit {check.scan_fit:.2f}"
    return f"{'pass' if check.passed else 'fail'}: missed {check.missed_predictions}/{check.predicted}{fit}"


def print_report(report: MatchReport, console: Console, checks: Sequence[Verification | None] = ()) -> None:
    """Confirmed features, the top-K hypotheses table (with each one's verification when
    ``checks`` are given), then the verdict line (last line)."""
    feats = Table(
        title=f"Confirmed features S_object ({len(report.features)}, odom frame)", title_justify="left"
    )
    for col in ("#", "class", "x [m]", "y [m]", "sightings", "confirmed t [s]"):
        feats.add_column(col, justify="right" if col not in ("class",) else "left")
    for f in report.features:
        feats.add_row(
            str(f.index + 1),
            f.cls,
            f"{f.x:.3f}",
            f"{f.y:.3f}",
            "given" if f.given else str(f.sightings),
            f"{f.t_confirmed:.2f}",
        )
    console.print(feats)

    if report.hypotheses:
        shown = len(report.hypotheses)
        title = (
            f"Hypotheses: top {shown} of {report.n_hypotheses} (pose method {report.options.pose_method}, "
            f"pose at the last odom record, BIM frame)"
        )
        table = Table(title=title, title_justify="left")
        for col in (
            "rank",
            "cost J",
            "storey",
            "matches (detection order)",
            "pose x y yaw",
            "rectified pose",
            "confidence",
            *(["checks"] if checks else []),
        ):
            table.add_column(
                col, justify="left" if col in ("storey", "matches (detection order)") else "right"
            )
        for i, h in enumerate(report.hypotheses):
            matches = " ".join(m if m is not None else "-" for m in h.matches)
            rect = _fmt_pose(h.rectified_pose) if h.rectified_pose is not None else "(no walls)"
            table.add_row(
                str(h.rank),
                f"{h.cost:.3f}",
                h.storey or "-",
                matches,
                _fmt_pose(h.pose),
                rect,
                f"{h.confidence:.3f}",
                *([_fmt_checks(checks[i])] if checks else []),
            )
        console.print(table)
        if any(h.n_outliers for h in report.hypotheses):
            console.print("'-' in matches: a detection treated as an outlier (--max-outliers)", style="dim")
    if report.truth is not None and report.hypotheses:
        best = report.hypotheses[0].pose
        console.print(
            f"truth (from the log): {_fmt_pose(report.truth)}; best hypothesis error "
            f"{best.distance_to(report.truth):.3f} m, {math.degrees(best.yaw_error(report.truth)):.2f}°",
            style="dim",
        )
    for note in report.notes:
        console.print(f"note: {note}", style="dim")
    console.print(report.verdict, style="bold", highlight=False)


_DEFAULTS = MatchOptions()  # every option's default below is the record's


def match(
    log: Annotated[Path, typer.Argument(metavar="LOG.jsonl", help="Detection log (JSON Lines, version 1).")],
    site: Annotated[
        Path, typer.Option("--site", metavar="SITE", help="bim-extract OUTDIR, or a features.csv (Table 1).")
    ],
    storey: Annotated[
        str,
        typer.Option("--storey", metavar="NAME|auto", help="Storey to match against; auto: every storey."),
    ] = _DEFAULTS.storey or "auto",
    alpha: Annotated[
        float, typer.Option("--alpha", metavar="M", help="Distance threshold of Eq. 7, metres.")
    ] = _DEFAULTS.alpha,
    beta: Annotated[
        float, typer.Option("--beta", metavar="DEG", help="Angle threshold of Eq. 9, degrees.")
    ] = _DEFAULTS.beta,
    top: Annotated[int, typer.Option("--top", metavar="K", help="Hypotheses to show.")] = _DEFAULTS.top,
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
    ] = _DEFAULTS.revisits,
    max_outliers: Annotated[
        int, typer.Option("--max-outliers", metavar="N", help="False or misclassified detections tolerated.")
    ] = _DEFAULTS.max_outliers,
    outlier_share: Annotated[
        float,
        typer.Option(
            "--outlier-share",
            metavar="S",
            help="With no match at --max-outliers, let the outlier budget grow up to this share of the "
            "features (0-0.5; 0: --max-outliers alone).",
        ),
    ] = _DEFAULTS.outlier_share,
    pose_method: Annotated[
        str,
        typer.Option(
            "--pose-method", metavar="paper|rigid", help="paper: Eq. 10-13; rigid: Kabsch on all matches."
        ),
    ] = _DEFAULTS.pose_method,
    pose_window: Annotated[
        int,
        typer.Option(
            "--pose-window",
            metavar="N",
            help="rigid: align the last N matched features (odometry drifts); 0: all of them.",
        ),
    ] = _DEFAULTS.pose_window,
    d_thre: Annotated[
        float, typer.Option("--d-thre", metavar="M", help="Wall clearance of Eq. 17, metres.")
    ] = _DEFAULTS.d_thre,
    min_sightings: Annotated[
        int, typer.Option("--min-sightings", metavar="K", help="Sightings that confirm a feature.")
    ] = _DEFAULTS.min_sightings,
    merge_radius: Annotated[
        float,
        typer.Option("--merge-radius", metavar="M", help="Same-class sightings closer than this merge."),
    ] = _DEFAULTS.merge_radius,
    score_threshold: Annotated[
        float, typer.Option("--score-threshold", metavar="S", help="Detections scoring lower are ignored.")
    ] = _DEFAULTS.score_threshold,
    min_depth: Annotated[
        float,
        typer.Option("--min-depth", metavar="M", help="Detections with a depth below this are ignored."),
    ] = _DEFAULTS.min_depth,
    max_depth: Annotated[
        float,
        typer.Option("--max-depth", metavar="M", help="Detections with a depth above this are ignored."),
    ] = _DEFAULTS.max_depth,
    edge_margin: Annotated[
        float,
        typer.Option(
            "--edge-margin",
            metavar="PX",
            help="Boxes this close to the left/right image border are cut off and not used; < 0 keeps them.",
        ),
    ] = _DEFAULTS.edge_margin,
    drift_window: Annotated[
        float | None,
        typer.Option(
            "--drift-window",
            metavar="M",
            help="Match only the features confirmed in the last M metres of travel (odometry drift).",
        ),
    ] = _DEFAULTS.drift_window,
    skip_bad: Annotated[
        bool, typer.Option("--skip-bad", help="Skip malformed log lines (with a count) instead of failing.")
    ] = _DEFAULTS.skip_bad,
) -> None:
    """Offline feature matching: confirmed features, ranked pose hypotheses and a verdict.

    Exit codes: 0 unique match, 3 several hypotheses, 4 no consistent match, 2 bad input.
    """
    options = MatchOptions(
        storey=None if storey.strip().lower() == "auto" else storey,
        alpha=alpha,
        beta=beta,
        top=top,
        max_outliers=max_outliers,
        outlier_share=outlier_share,
        revisits=revisits,
        pose_method=pose_method,
        pose_window=pose_window,
        d_thre=d_thre,
        min_sightings=min_sightings,
        merge_radius=merge_radius,
        score_threshold=score_threshold,
        min_depth=min_depth,
        max_depth=max_depth,
        edge_margin=edge_margin,
        drift_window=drift_window,
        skip_bad=skip_bad,
    )
    checks = None
    verify = site.is_dir()  # the checks need the site's maps; a bare features.csv has none
    try:
        if plot is not None:
            from initcli.cli.plot_hypotheses import PLOT_SUFFIXES

            check_outputs([log, site], [OutputFile(plot, "--plot", PLOT_SUFFIXES)])
        with message_progress() as progress, log_or_bag(log, progress=progress) as log_path:
            options.validate()
            listed = replace(options, top=max(top, TRACK_HYPOTHESES)) if verify else options
            report = run_match(log_path, site, listed)
            if verify:
                checks = check_hypotheses(log_path, site, report, options.skip_bad, top)
    except InputError as exc:
        raise _fail(str(exc)) from None

    for warning in report.warnings:
        typer.echo(f"bim-init: warning: {warning}", err=True)
    if json_out:
        typer.echo(json.dumps(report_to_dict(report, checks), indent=2))
    else:
        console = Console(width=None if sys.stdout.isatty() else 200, soft_wrap=False)
        print_report(report, console, checks or ())
    if plot is not None:
        from initcli.cli.plot_hypotheses import plot_hypotheses

        try:
            plot_hypotheses(report, plot)
        except OSError as exc:
            raise _fail(f"{plot}: cannot write the plot: {exc.strerror or exc}") from None
    raise typer.Exit(report.exit_code)
