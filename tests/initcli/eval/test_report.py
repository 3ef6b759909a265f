"""The evaluation's tables and plots from trial records (initcli.eval.report, initcli.eval.plots)."""

from __future__ import annotations

from pathlib import Path

from initcli.eval import plots
from initcli.eval.records import FailureRule, TrialRecord
from initcli.eval.report import table_markdown, write_report
from initcli.eval.scoring import summarise


def record(site: str, start: int, method: str, ok: bool, error: float, distance: float) -> TrialRecord:
    return TrialRecord(
        site=site,
        start=start,
        method=method,
        success=ok,
        reason="localised" if ok else "no result",
        features=5,
        distance_m=distance,
        error_translation_m=error if ok else None,
        error_rotation_deg=1.0 if ok else None,
        confident_wrong=False,
        seconds=0.1,
    )


RECORDS = [
    record("block_a", k, m, ok=(m != "amcl" or k == 0), error=0.05 * (k + 1), distance=10.0 + k)
    for k in range(3)
    for m in ("bim", "bim+pf", "amcl")
]


def test_write_report_writes_every_table_and_figure(tmp_path: Path) -> None:
    summaries = write_report(tmp_path, RECORDS, {"block_a": "BlockA"}, FailureRule(), None, "bim-init eval")
    names = {p.name for p in tmp_path.iterdir()}
    assert {"table.csv", "table.md", "fig9.png", "fig12_block_a.png"} <= names
    by_method = {s.method: s for s in summaries}
    assert by_method["bim"].success_rate == 100.0  # per cent
    assert abs(by_method["amcl"].success_rate - 100 / 3) < 1e-6
    text = (tmp_path / "table.md").read_text()
    assert "block_a" in text and "(paper)" in text
    assert (tmp_path / "fig9.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_table_markdown_puts_the_paper_beside_ours() -> None:
    text = table_markdown(summarise(RECORDS), {"block_a": "BlockA"}, FailureRule(), None, "cmd")
    assert "14.81" in text  # the paper's BlockA distance to the coarse result (Table 2)


def test_fig12_draws_one_site(tmp_path: Path) -> None:
    plots.fig12(RECORDS, "block_a", tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 1000
