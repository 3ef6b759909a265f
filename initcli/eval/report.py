"""Everything ``bim-init eval`` writes after the trials: table.csv, table.md and the plots."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from bimkit.atomic import write_text_atomic
from initcli.eval import plots
from initcli.eval.consistency import consistency_rows
from initcli.eval.records import FailureRule, MethodSummary, TrialRecord
from initcli.eval.results_file import write_csv
from initcli.eval.scoring import summarise
from initcli.eval.tables import CSV_COLUMNS, csv_rows, markdown, sweep_table, table2, table3
from initcli.eval.watch_table import watch_rows

CONSISTENCY_NOTE = (
    "What Nav2 is sent with the pose: is the error inside its own covariance? NEES: the error (x, y,"
    " yaw) weighed by the inverse covariance; inside the 99 % ellipse below 11.345 (chi-square, 3"
    " degrees of freedom), so about 99 % of honest poses are."
)

WATCH_NOTE = (
    "The robot starts with its localiser right (a stand-in: the truth with a little noise), explores,"
    " and after `sim.kidnap` m is carried to a random free place, its wheels unaware; the stand-in"
    " keeps tracking the old place by odometry. False alarms: `lost` while the localiser was right,"
    " per km of such travel."
)

__all__ = ["RunStats", "table_markdown", "write_report"]


@dataclass(frozen=True)
class RunStats:
    """How fast this invocation ran its trials (the benchmark the issue asks for)."""

    trials: int
    seconds: float
    workers: int

    @property
    def per_minute(self) -> float:
        return 60.0 * self.trials / self.seconds if self.seconds > 0 else 0.0


def table_markdown(
    summaries: list[MethodSummary],
    environments: dict[str, str | None],
    rule: FailureRule,
    stats: RunStats | None,
    command: str,
    watched: list[TrialRecord] | None = None,
    records: list[TrialRecord] | None = None,
) -> str:
    """table.md: the paper's tables, the sweeps, the watch's trials (``watched``) and the rate."""
    parts = ["# bim-init eval", "", f"Command: `{command}`", ""]
    parts += [
        f"Failure rule (paper §4.3): more than {rule.max_distance_m:g} m moved without a result, or a "
        f"final error above {rule.max_error_m:g} m. Distance, features and errors are averaged over "
        f"successful trials only, as in the paper; a confident wrong result is a claimed pose more "
        f"than {rule.wrong_error_m:g} m or {rule.wrong_error_deg:g} degrees from the truth. "
        "`(paper)` columns: the paper's published means "
        "(Table 2 for every environment, Table 3 for the baselines on the NTU floor).",
        "",
    ]
    summaries = [s for s in summaries if s.method != "watch"]  # another task: its own table below
    header, rows = table2(summaries, environments)
    if rows:
        parts += ["## Table 2: BIM-based initialisation per site", "", markdown(header, rows), ""]
    header, rows = table3(summaries, environments)
    if rows:
        parts += ["## Table 3: methods compared", "", markdown(header, rows), ""]
    header, rows = sweep_table(summaries)
    if rows:
        parts += ["## Robustness sweeps", "", markdown(header, rows), ""]
    header, rows = consistency_rows(records or [])
    if rows:
        parts += ["## Pose and covariance", "", CONSISTENCY_NOTE, "", markdown(header, rows), ""]
    if watched:
        header, rows = watch_rows(watched)
        parts += ["## Lost and found (bim-init watch)", "", WATCH_NOTE, "", markdown(header, rows), ""]
    if stats is not None and stats.trials:
        parts += [
            f"Trial rate: {stats.trials} trials in {stats.seconds:.0f} s on {stats.workers} worker(s) = "
            f"{stats.per_minute:.1f} trials/min.",
            "",
        ]
    return "\n".join(parts)


def write_report(
    out: Path,
    records: list[TrialRecord],
    environments: dict[str, str | None],
    rule: FailureRule,
    stats: RunStats | None,
    command: str,
) -> list[MethodSummary]:
    """Write table.csv, table.md, fig9.png, fig12_<site>.png and sweep_<key>.png into ``out``."""
    summaries = summarise(records)
    write_csv(out / "table.csv", CSV_COLUMNS, csv_rows(summaries, environments))
    watched = [r for r in records if r.method == "watch"]
    write_text_atomic(
        out / "table.md", table_markdown(summaries, environments, rule, stats, command, watched, records)
    )
    plain = [r for r in records if not r.sweep_key]
    if any(r.method in ("bim", "bim+pf") for r in plain):
        plots.fig9(plain, out / "fig9.png")
    for site in dict.fromkeys(r.site for r in plain):
        plots.fig12(plain, site, out / f"fig12_{site}.png")
    for key in dict.fromkeys(r.sweep_key for r in records if r.sweep_key):
        plots.sweep_plot(summaries, key, out / f"sweep_{key}.png")
    return summaries
