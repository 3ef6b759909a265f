"""Paths the tests share: the repository root, the bundled samples, the real IFC models in ../shared/ifc;
how a session's claim replays from its log; the map of a few closed rooms; walls drawn into a grid.

Test modules import these as ``from tests.helpers import SAMPLES`` (pytest's ``pythonpath`` puts the
repository root on ``sys.path``); the fixtures built on them live in ``tests/conftest.py``.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

    from bimtools.extract.pipeline import ExtractedSite
    from bimtools.site.records import OccupancyGrid
    from initcli.match.pipeline import Hypothesis, MatchReport

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_models"
SCHEMAS = ROOT / "schemas"
SHARED_IFC = ROOT.parent / "shared" / "ifc"


def extracted_all_storeys(path: Path) -> ExtractedSite:
    """``extract_site(path, storey="all")`` once per test session: the real models take a minute each,
    and two test modules read them."""
    return _extracted(Path(path).resolve())


@functools.cache
def _extracted(path: Path) -> ExtractedSite:
    from bimtools.extract.pipeline import extract_site

    return extract_site(path, storey="all")


def shared_ifc_files() -> list[Path]:
    """The real IFC models in ../shared/ifc, sorted (none when the folder is absent)."""
    return sorted(SHARED_IFC.glob("*.ifc")) if SHARED_IFC.is_dir() else []


def replayed_claim(log_path: Path, site_dir: Path, report: MatchReport) -> Hypothesis:
    """What a session claimed, as ``bim-init match`` finds it in the session's log (``report``, its
    match): the unique match, or of several hypotheses the one the lidar along the path favours
    (a session checks that one as a unique match), or else the lidar registration's place."""
    import copy

    from bimtools.site.load import load_site
    from initcli.core.lidar.registration_params import RegistrationParams
    from initcli.io.detection_log import read_log
    from initcli.match.pipeline import site_class_map
    from initcli.verify.evidence import verify_and_favour
    from initcli.verify.registration import DECIDED_BY_REGISTRATION, replay_registration

    if report.verdict == "unique match":
        return report.hypotheses[0]
    site, log = load_site(site_dir), read_log(log_path)
    checks, favoured = verify_and_favour(log, site, report, site_class_map(site))
    if favoured is not None:
        return report.hypotheses[favoured]
    replayed = copy.deepcopy(report)  # the caller's report stays Algorithm 1's
    replay_registration(log, site, replayed, list(checks), RegistrationParams(), len(report.hypotheses) + 1)
    assert replayed.decided_by == DECIDED_BY_REGISTRATION, (
        f"{report.verdict}, and neither the lidar along the path nor a registration decides"
    )
    return replayed.hypotheses[0]


def rooms_map(
    rooms: list[tuple[float, float, float, float]], width: float, height: float, res: float = 0.05
) -> OccupancyGrid:
    """The occupancy grid of closed rectangular ``rooms`` (x0, y0, x1, y1 m): their walls one cell
    thick and occupied, inside free, the rest unknown; ``width`` x ``height`` m from (-2, -2)."""
    import numpy as np

    from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

    x0, y0 = -2.0, -2.0
    cells = np.full((int(height / res), int(width / res)), UNKNOWN, dtype=np.uint8)
    rows = cells.shape[0]

    def row(y: float) -> int:
        return rows - 1 - int((y - y0) / res)

    def col(x: float) -> int:
        return int((x - x0) / res)

    for left, bottom, right, top in rooms:
        cells[row(top) : row(bottom) + 1, col(left) : col(right) + 1] = OCCUPIED
        cells[row(top) + 1 : row(bottom), col(left) + 1 : col(right)] = FREE
    return OccupancyGrid(cells, res, (x0, y0, 0.0))


def wait_until(predicate: Callable[[], object], timeout: float) -> bool:
    """Whether ``predicate()`` came true within ``timeout`` seconds (polled every 20 ms)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return False


def walls_grid(
    walls: np.ndarray, res: float = 0.05, bounds: tuple[float, float, float, float] | None = None
) -> OccupancyGrid:
    """Wall segments (N x 4: x1, y1, x2, y2) drawn one cell thick into an occupancy grid of ``res`` m
    cells, free elsewhere, over ``bounds`` (x0, y0, x1, y1; default: the walls' box and 1 m more)."""
    import numpy as np

    from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid

    if bounds is None:
        bounds = (
            walls[:, [0, 2]].min() - 1.0,
            walls[:, [1, 3]].min() - 1.0,
            walls[:, [0, 2]].max() + 1.0,
            walls[:, [1, 3]].max() + 1.0,
        )
    x0, y0 = bounds[0], bounds[1]
    w, h = int(round((bounds[2] - x0) / res)), int(round((bounds[3] - y0) / res))
    cells = np.full((h, w), FREE, dtype=np.uint8)
    for x1, y1, x2, y2 in walls:
        n = int(max(abs(x2 - x1), abs(y2 - y1)) / res) + 1
        cols = np.floor((np.linspace(x1, x2, n) - x0) / res).astype(int)
        rows = h - 1 - np.floor((np.linspace(y1, y2, n) - y0) / res).astype(int)
        cells[rows, cols] = OCCUPIED
    return OccupancyGrid(cells, res, (x0, y0, 0.0))
