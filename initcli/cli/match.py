"""``bim-init match``: a detection log against the feature table, and the console tables of the result.

Exit codes: 0 unique match, 3 ambiguous (several hypotheses), 4 no consistent match, 2 bad input
(one line on stderr, never a traceback).
"""

from __future__ import annotations

import inspect
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from bimkit.cli import fail
from bimkit.errors import InputError
from bimkit.outputs import OutputFile, check_outputs
from bimkit.ownership import drawn_by_matplotlib
from bimkit.settings import describe, settings_of
from initcli.cli import PROG
from initcli.cli.bag_options import (
    BaseFrame,
    CameraInfoTopic,
    ClassNames,
    DepthTopic,
    DetectionsTopic,
    ImageTopic,
    Model,
    OdomTopic,
    Rate,
    ScanTopic,
    bag_options,
)
from initcli.cli.exit_codes import match_exit_code
from initcli.cli.progress import message_progress
from initcli.config.matching import MatchOptions
from initcli.core.geometry.se2 import Pose2D
from initcli.core.verify.checks import TRACK_HYPOTHESES, Verification
from initcli.io.detection_log import read_meta
from initcli.match.pipeline import run_match
from initcli.match.recorded import recorded_settings
from initcli.match.report import MatchReport
from initcli.match.report_file import report_to_dict
from initcli.ros.convert import log_or_bag
from initcli.verify.registration import check_and_register

__all__ = ["match", "print_report"]


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
            # a lidar registration's place matches no feature and is not rectified
            rect = (
                _fmt_pose(h.rectified_pose)
                if h.rectified_pose is not None
                else "(no walls)"
                if h.matches
                else "-"
            )
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


def _record_options(record: type) -> list[inspect.Parameter]:
    """An option of the command for each setting of ``record`` with a ``metavar`` (a value) or a
    ``flag`` (a switch): its name, default, help (the setting's description and range) and type are
    the field's, so a setting added to :class:`MatchOptions` is an option with no other edit."""
    params = []
    for f, meta, tp in settings_of(record):
        if meta.metavar is None and meta.flag is None:
            continue
        text = describe(meta, tp is int)
        if meta.flag is not None:
            option = typer.Option(meta.flag, help=text)
        else:
            option = typer.Option("--" + f.name.replace("_", "-"), metavar=meta.metavar, help=text)
        params.append(
            inspect.Parameter(
                f.name, inspect.Parameter.KEYWORD_ONLY, default=f.default, annotation=Annotated[tp, option]
            )
        )
    return params


def _given_options(ctx: typer.Context) -> set[str]:
    """The names of the options the user gave on the command line (the others are defaults, which
    a session's log may replace with what the session ran with)."""
    given = set()
    for name in ctx.params:
        source = ctx.get_parameter_source(name)
        if source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP"):
            given.add(name)
    return given


def match(
    ctx: typer.Context,
    log: Annotated[Path, typer.Argument(metavar="LOG.jsonl", help="Detection log (JSON Lines, version 1).")],
    site: Annotated[
        Path, typer.Option("--site", metavar="SITE", help="bim-extract OUTDIR, or a features.csv (Table 1).")
    ],
    storey: Annotated[
        str,
        typer.Option("--storey", metavar="NAME|auto", help="Storey to match against; auto: every storey."),
    ] = "auto",
    json_out: Annotated[
        bool, typer.Option("--json", help="Print one JSON document instead of tables.")
    ] = False,
    plot: Annotated[
        Path | None, typer.Option("--plot", metavar="FILE.png", help="Draw the hypotheses on the floor plan.")
    ] = None,
    image_topic: ImageTopic = None,
    detections_topic: DetectionsTopic = None,
    depth_topic: DepthTopic = None,
    camera_info_topic: CameraInfoTopic = None,
    odom_topic: OdomTopic = None,
    scan_topic: ScanTopic = None,
    base_frame: BaseFrame = None,
    model: Model = "default",
    rate: Rate = None,
    class_names: ClassNames = None,
    **settings: Any,
) -> None:
    """Offline feature matching: confirmed features, ranked pose hypotheses and a verdict. LOG may
    be a ROS bag, read as ``bim-init bag2log`` reads it (its options are the bag's).

    Exit codes: 0 unique match, 3 several hypotheses, 4 no consistent match, 2 bad input.
    """
    options = MatchOptions(storey=None if storey.strip().lower() == "auto" else storey, **settings)
    given = _given_options(ctx)
    top = options.top
    checks = None
    verify = site.is_dir()  # the checks need the site's maps; a bare features.csv has none
    try:
        bag = bag_options(
            image_topic,
            detections_topic,
            depth_topic,
            camera_info_topic,
            odom_topic,
            scan_topic,
            base_frame,
            model,
            rate,
            class_names,
        )
        inputs = [log, site, None if model == "default" else Path(model)]
        if plot is not None:
            from initcli.cli.plot_hypotheses import PLOT_SUFFIXES

            plots = OutputFile(plot, "--plot", PLOT_SUFFIXES, owned=drawn_by_matplotlib, kind="plot")
            check_outputs(inputs, [plots])
        with message_progress() as progress, log_or_bag(log, bag, progress) as log_path:
            options.validate()
            # a session's log: the storey and settings it recorded for the options not given
            meta = read_meta(log_path)
            recorded = recorded_settings(meta, options, given, str(log))
            options = recorded.options
            listed = replace(options, top=max(top, TRACK_HYPOTHESES)) if verify else options
            report = run_match(log_path, site, listed, source=log)
            if recorded.note is not None:
                report.notes.insert(0, recorded.note)
            camera_absent = meta is not None and meta.camera_absent
            if verify:
                checks = check_and_register(
                    log_path, site, report, options.skip_bad, top, recorded.registration
                )
    except InputError as exc:
        fail(PROG, exc)

    for warning in report.warnings:
        typer.echo(f"bim-init: warning: {warning}", err=True)
    code = match_exit_code(report.outcome)
    if json_out:
        doc = {**report_to_dict(report, checks, exit_code=code), "camera_absent": camera_absent}
        typer.echo(json.dumps(doc, indent=2))
    else:
        console = Console(width=None if sys.stdout.isatty() else 200, soft_wrap=False)
        print_report(report, console, checks or ())
    if plot is not None:
        from initcli.cli.plot_hypotheses import plot_hypotheses

        try:
            plot_hypotheses(report, plot)
        except OSError as exc:
            fail(PROG, f"{plot}: cannot write the plot: {exc.strerror or exc}")
    raise typer.Exit(code)


# The command's parameters: the ones above, then an option per setting of MatchOptions (typer reads
# the signature).
_HAND = list(inspect.signature(match, eval_str=True).parameters.values())[:-1]
match.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
    [*_HAND, *_record_options(MatchOptions)], return_annotation=None
)
