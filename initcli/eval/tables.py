"""The paper's Table 2 and Table 3 layouts from our summaries, with the paper's figures beside."""

from __future__ import annotations

import dataclasses

from initcli.eval.paper import METHOD_TITLES, paper_row
from initcli.eval.records import MethodSummary

__all__ = ["CSV_COLUMNS", "NONE", "csv_rows", "fmt", "markdown", "sweep_table", "table2", "table3"]

NONE = "—"

CSV_COLUMNS = [f.name for f in dataclasses.fields(MethodSummary)] + [
    "paper_environment",
    "paper_success_rate",
    "paper_features",
    "paper_distance_m",
    "paper_error_translation_m",
    "paper_error_rotation_deg",
]


def fmt(value: float | None, digits: int = 2) -> str:
    return NONE if value is None else f"{value:.{digits}f}"


def csv_rows(summaries: list[MethodSummary], environments: dict[str, str | None]) -> list[dict[str, object]]:
    """``table.csv``: one row per (site, method, sweep value): every statistic, then the paper's."""
    rows = []
    for s in summaries:
        row: dict[str, object] = dataclasses.asdict(s)
        env = environments.get(s.site)
        paper = paper_row(env, s.method)
        row["paper_environment"] = env or ""
        for key, value in (
            ("paper_success_rate", paper.success_rate if paper else None),
            ("paper_features", paper.features if paper else None),
            ("paper_distance_m", paper.distance_m if paper else None),
            ("paper_error_translation_m", paper.error_translation_m if paper else None),
            ("paper_error_rotation_deg", paper.error_rotation_deg if paper else None),
        ):
            row[key] = value
        rows.append(
            {k: ("" if v is None else round(v, 4) if isinstance(v, float) else v) for k, v in row.items()}
        )
    return rows


def table2(
    summaries: list[MethodSummary], environments: dict[str, str | None]
) -> tuple[list[str], list[list[str]]]:
    """Table 2: per site, features, distance and errors after rectification and after fine tuning."""
    header = [
        "Site",
        "Features",
        "(paper)",
        "Distance coarse m",
        "(paper)",
        "Rect. error m",
        "(paper)",
        "Rect. error °",
        "(paper)",
        "Distance total m",
        "(paper)",
        "PF error m",
        "(paper)",
        "PF error °",
        "(paper)",
    ]
    by = {(s.site, s.method): s for s in summaries if not s.sweep_key}
    rows = []
    for site in dict.fromkeys(s.site for s in summaries if not s.sweep_key):
        bim, pf = by.get((site, "bim")), by.get((site, "bim+pf"))
        either = bim or pf
        if either is None:
            continue
        env = environments.get(site)
        pb, pp = paper_row(env, "bim"), paper_row(env, "bim+pf")
        label = f"{site} ({env})" if env else site
        rows.append(
            [
                label,
                fmt(either.features_mean, 1),
                fmt(pb.features if pb else None, 0),
                fmt(bim.distance_mean_m if bim else None, 1),
                fmt(pb.distance_m if pb else None, 2),
                fmt(bim.error_translation_mean_m if bim else None, 3),
                fmt(pb.error_translation_m if pb else None, 2),
                fmt(bim.error_rotation_mean_deg if bim else None, 2),
                fmt(pb.error_rotation_deg if pb else None, 2),
                fmt(pf.distance_mean_m if pf else None, 1),
                fmt(pp.distance_m if pp else None, 2),
                fmt(pf.error_translation_mean_m if pf else None, 3),
                fmt(pp.error_translation_m if pp else None, 2),
                fmt(pf.error_rotation_mean_deg if pf else None, 2),
                fmt(pp.error_rotation_deg if pp else None, 2),
            ]
        )
    return header, rows


def table3(
    summaries: list[MethodSummary], environments: dict[str, str | None], long_names: bool = True
) -> tuple[list[str], list[list[str]]]:
    """Table 3: per site and method, success rate, distance and errors, plus medians, P95 and
    confident wrong results (ours only; the paper published means)."""
    header = [
        "Site",
        "Method",
        "Success %",
        "(paper)",
        "Distance m",
        "(paper)",
        "Error m",
        "(paper)",
        "Error °",
        "(paper)",
        "Error m median / P95",
        "Error ° median / P95",
        "Confident wrong",
        "Trials",
        "Refused",
        "s / trial",
    ]
    rows = []
    for s in summaries:
        if s.sweep_key:
            continue
        env = environments.get(s.site)
        p = paper_row(env, s.method)
        rows.append(
            [
                f"{s.site} ({env})" if env else s.site,
                METHOD_TITLES.get(s.method, s.method) if long_names else s.method,
                fmt(s.success_rate, 0),
                fmt(p.success_rate if p else None, 0),
                fmt(s.distance_mean_m, 1),
                fmt(p.distance_m if p else None, 2),
                fmt(s.error_translation_mean_m, 3),
                fmt(p.error_translation_m if p else None, 2),
                fmt(s.error_rotation_mean_deg, 2),
                fmt(p.error_rotation_deg if p else None, 2),
                f"{fmt(s.error_translation_median_m, 3)} / {fmt(s.error_translation_p95_m, 3)}",
                f"{fmt(s.error_rotation_median_deg, 2)} / {fmt(s.error_rotation_p95_deg, 2)}",
                str(s.confident_wrong),
                str(s.trials),
                str(s.refused),
                fmt(s.seconds_mean, 2),
            ]
        )
    return header, rows


def sweep_table(summaries: list[MethodSummary]) -> tuple[list[str], list[list[str]]]:
    """Success and mean error of each method at each swept value (all sites together per row)."""
    header = [
        "Parameter",
        "Value",
        "Site",
        "Method",
        "Success %",
        "Error m",
        "Error °",
        "Distance m",
        "Confident wrong",
    ]
    rows = [
        [
            s.sweep_key,
            s.sweep_value,
            s.site,
            s.method,
            fmt(s.success_rate, 0),
            fmt(s.error_translation_mean_m, 3),
            fmt(s.error_rotation_mean_deg, 2),
            fmt(s.distance_mean_m, 1),
            str(s.confident_wrong),
        ]
        for s in summaries
        if s.sweep_key
    ]
    return header, rows


def markdown(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)
