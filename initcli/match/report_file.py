"""The JSON document of a :class:`~initcli.match.report.MatchReport` (``bim-init match --json``).

The JSON document follows ``schemas/match_result.schema.json``; its poses are rounded to
:data:`~initcli.core.geometry.se2.MATCH_DIGITS`.
"""

from __future__ import annotations

from typing import Any

from initcli.core.geometry.se2 import MATCH_DIGITS, Pose2D, pose_json
from initcli.match.report import MatchReport

__all__ = ["RESULT_FORMAT", "report_to_dict"]

RESULT_FORMAT = "bim-init.match/1"


def _pose(p: Pose2D | None) -> dict[str, float] | None:
    return None if p is None else pose_json(p, MATCH_DIGITS)


def report_to_dict(
    report: MatchReport, verifications: list[Any] | None = None, *, exit_code: int
) -> dict[str, Any]:
    """The ``--json`` document; ``verifications``: one check per hypothesis (or None) to include;
    ``exit_code``: the command's exit code for the report's outcome, which the document records
    (the command's to tell: ``initcli.cli.exit_codes``)."""
    o = report.options
    checks = verifications if verifications is not None else [None] * len(report.hypotheses)
    return {
        "format": RESULT_FORMAT,
        "verdict": report.verdict,
        "exit_code": exit_code,
        "decided_by": report.decided_by,
        "paper_verdict": report.paper_verdict or report.verdict,
        "registration": None if report.registration is None else report.registration.as_dict(),
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
                "verification": check.as_dict() if check is not None else None,
            }
            for h, check in zip(report.hypotheses, checks, strict=True)
        ],
        "parameters": {
            "alpha": o.alpha,
            "beta_deg": o.beta,  # the JSON key keeps its unit
            "top": o.top,
            "max_outliers": o.max_outliers,
            "outlier_share": o.outlier_share,
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
