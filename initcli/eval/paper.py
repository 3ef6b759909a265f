"""The paper's published figures (§4, Tables 2 and 3), printed beside ours."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["METHOD_TITLES", "PAPER", "PaperRow", "paper_row"]


@dataclass(frozen=True)
class PaperRow:
    success_rate: float | None  # percent
    features: float | None
    distance_m: float | None
    error_translation_m: float | None
    error_rotation_deg: float | None


# Table 2: per environment, coarse + BIM rectification and + PF fine tuning (all trials succeeded).
# Table 3 (NTU only): the two baselines.
PAPER: dict[str, dict[str, PaperRow]] = {
    "NTU": {
        "bim": PaperRow(100.0, 4, 44.88, 0.61, 8.91),
        "bim+pf": PaperRow(100.0, 4, 50.32, 0.21, 1.47),
        "markers": PaperRow(94.0, None, 51.21, 0.17, 2.75),
        "amcl": PaperRow(35.0, None, 12.00, 1.04, 1.43),
    },
    "BlockA": {
        "bim": PaperRow(100.0, 4, 14.81, 0.37, 5.00),
        "bim+pf": PaperRow(100.0, 4, 21.99, 0.12, 2.39),
    },
    "BlockB": {
        "bim": PaperRow(100.0, 5, 16.61, 0.26, 4.69),
        "bim+pf": PaperRow(100.0, 5, 22.76, 0.15, 1.18),
    },
}

METHOD_TITLES = {
    "bim": "BIM-based rectification",
    "bim+pf": "BIM-based + PF-based fine tuning",
    "markers": "Fiducial markers (ArUco-like)",
    "amcl": "AMCL global localisation",
}


def paper_row(environment: str | None, method: str) -> PaperRow | None:
    if environment is None:
        return None
    return PAPER.get(environment, {}).get(method)
