"""Is the covariance sent with a pose honest? ``table.md``'s "Pose and covariance" table: per site
and method with a covariance (``bim+pf``), the share of claimed poses whose error lies inside the
99 % ellipse of their own covariance (NEES over x, y, yaw below the chi-square 99 % point with 3
degrees of freedom) and the overconfident ones (more than :data:`OVERCONFIDENT_M` m off with a
sigma under :data:`OVERCONFIDENT_SIGMA_M` m)."""

from __future__ import annotations

import statistics

from initcli.eval.records import TrialRecord
from initcli.eval.tables import NONE

__all__ = ["CHI2_99_3DOF", "OVERCONFIDENT_M", "OVERCONFIDENT_SIGMA_M", "consistency_rows", "overconfident"]

CHI2_99_3DOF = 11.345  # the 99 % point of the chi-square distribution with 3 degrees of freedom
OVERCONFIDENT_M = 0.3  # m: a pose this far off ...
OVERCONFIDENT_SIGMA_M = 0.1  # m: ... claimed with a sigma under this is overconfident


def overconfident(record: TrialRecord) -> bool:
    return (
        record.sigma_m is not None
        and record.error_translation_m is not None
        and record.error_translation_m > OVERCONFIDENT_M
        and record.sigma_m < OVERCONFIDENT_SIGMA_M
    )


def consistency_rows(records: list[TrialRecord]) -> tuple[list[str], list[list[str]]]:
    """One row per (site, method) whose records carry a NEES; none when no record does."""
    header = ["site", "method", "poses with a covariance", "inside the 99 % ellipse", "median NEES"]
    header += [
        f"overconfident (> {OVERCONFIDENT_M:g} m, sigma < {OVERCONFIDENT_SIGMA_M:g} m)",
        "median sigma m",
    ]
    rows = []
    keys = sorted({(r.site, r.method) for r in records if r.nees is not None and not r.sweep_key})
    for site, method in keys:
        mine = [
            r
            for r in records
            if (r.site, r.method) == (site, method) and r.nees is not None and not r.sweep_key
        ]
        inside = sum(r.nees is not None and r.nees <= CHI2_99_3DOF for r in mine)
        sigmas = [r.sigma_m for r in mine if r.sigma_m is not None]
        rows.append(
            [
                site,
                method,
                str(len(mine)),
                f"{inside}/{len(mine)} ({100 * inside / len(mine):.0f} %)",
                f"{statistics.median(r.nees for r in mine if r.nees is not None):.2f}",
                str(sum(overconfident(r) for r in mine)),
                f"{statistics.median(sigmas):.3f}" if sigmas else NONE,
            ]
        )
    return header, rows
