"""The paper's published rows (Tables 2 and 3) looked up per environment and method."""

from __future__ import annotations

from initcli.eval.paper import METHOD_TITLES, PAPER, paper_row


def test_table_rows() -> None:
    ntu = paper_row("NTU", "bim+pf")
    assert ntu is not None and ntu.success_rate == 100.0 and ntu.error_translation_m == 0.21
    amcl = paper_row("NTU", "amcl")
    assert amcl is not None and amcl.success_rate == 35.0 and amcl.features is None
    assert paper_row("BlockA", "markers") is None  # Table 3 is NTU only
    assert paper_row("Elsewhere", "bim") is None and paper_row(None, "bim") is None


def test_every_method_has_a_title() -> None:
    methods = {m for rows in PAPER.values() for m in rows}
    assert methods == set(METHOD_TITLES) == {"bim", "bim+pf", "markers", "amcl"}
