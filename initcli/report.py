"""Rendering of a :class:`~initcli.match.MatchReport`: the console tables and the JSON document.

The JSON document follows ``schemas/match_result.schema.json``.
"""

from __future__ import annotations

import math
from typing import Any

from rich.console import Console
from rich.table import Table

from initcli.core.geometry import Pose2D
from initcli.match import MatchReport

RESULT_FORMAT = "bim-init.match/1"


def _pose(p: Pose2D | None) -> dict[str, float] | None:
    if p is None:
        return None
    return {
        "x": round(p.x, 6),
        "y": round(p.y, 6),
        "yaw": round(p.yaw, 6),
        "yaw_deg": round(math.degrees(p.yaw), 4),
    }


def report_to_dict(report: MatchReport) -> dict[str, Any]:
    """The ``--json`` document."""
    o = report.options
    return {
        "format": RESULT_FORMAT,
        "verdict": report.verdict,
        "exit_code": report.exit_code,
        "n_hypotheses": report.n_hypotheses,
        "storey": report.storey,
        "storeys_searched": list(report.storeys),
        "log": str(report.log),
        "site": str(report.site),
        "pose_method": o.pose_method,
        "odom_pose": _pose(report.odom_pose),
        "features": [
            {
                "index": f.index,
                "class": f.cls,
                "x": round(f.x, 6),
                "y": round(f.y, 6),
                "sightings": f.sightings,
                "t_first": f.t_first,
                "t_confirmed": f.t_confirmed,
                "given": f.given,
            }
            for f in report.features
        ],
        "hypotheses": [
            {
                "rank": h.rank,
                "cost": round(h.cost, 6),
                "storey": h.storey,
                "matches": list(h.matches),
                "outliers": h.n_outliers,
                "pose": _pose(h.pose),
                "rectified_pose": _pose(h.rectified_pose),
                "rectified": h.rectified,
                "confidence": round(h.confidence, 6),
                "support": h.support,
            }
            for h in report.hypotheses
        ],
        "parameters": {
            "alpha": o.alpha,
            "beta_deg": o.beta_deg,
            "top": o.top,
            "max_outliers": o.max_outliers,
            "min_inliers": o.min_inliers,
            "d_thre": o.d_thre,
            "pose_radius": o.pose_radius,
            "merge_radius": o.merge_radius,
            "min_sightings": o.min_sightings,
            "score_threshold": o.score_threshold,
            "min_depth": o.min_depth,
            "max_depth": o.max_depth,
        },
        "truth": _pose(report.truth),
        "warnings": list(report.warnings),
        "notes": list(report.notes),
    }


def _fmt_pose(p: Pose2D | None) -> str:
    if p is None:
        return "-"
    return f"{p.x:8.3f} {p.y:8.3f} {math.degrees(p.yaw):7.1f}°"


def print_report(report: MatchReport, console: Console) -> None:
    """Confirmed features, the top-K hypotheses table, then the verdict line (last line)."""
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
        ):
            table.add_column(
                col, justify="left" if col in ("storey", "matches (detection order)") else "right"
            )
        for h in report.hypotheses:
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
