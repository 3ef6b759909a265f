"""initcli.survey.plots: the survey heat map panel and survey_<storey>.png."""

from __future__ import annotations

import struct
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from bimtools.site.load import StoreyModel
from bimtools.site.records import FREE, OCCUPIED, Feature, OccupancyGrid, WallSegment
from initcli.survey.landmarks import suggest_landmarks
from initcli.survey.plan import SurveyParams, plan_storey
from initcli.survey.plots import _panel, survey_png
from initcli.survey.run import StoreySurvey, survey_storey

matplotlib.use("Agg")

PARAMS = SurveyParams(spacing=2.0, headings=2, limit_m=40.0, min_sightings=2)


def _room() -> StoreyModel:
    """An 8 m x 5 m walled room with two doors on one wall: never unique without a landmark."""
    cells = np.full((52, 82), FREE, dtype=np.uint8)
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = OCCUPIED
    features = [
        Feature("d1", "Door", 1.0, 0.0, 0.0, 1.0, 1.0, 2.1),
        Feature("d2", "Door", 2.5, 0.0, 0.0, 1.0, 1.0, 2.1),
    ]
    corners = [(0.0, 0.0), (8.0, 0.0), (8.0, 5.0), (0.0, 5.0), (0.0, 0.0)]
    normals = [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 0.0)]
    walls = [
        WallSegment("L0", f"w{i}", "IfcWall", *corners[i], *corners[i + 1], normals[i]) for i in range(4)
    ]
    return StoreyModel("L0", 0.0, features, walls, grid=OccupancyGrid(cells, 0.1, (-0.1, -0.1, 0.0)))


@pytest.fixture(scope="module")
def surveyed() -> tuple[StoreySurvey, object]:
    return survey_storey(plan_storey(_room(), PARAMS), PARAMS)


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_panel_marks_never_unique_positions_and_draws_walls(surveyed) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize

    result, _ = surveyed
    fig, ax = plt.subplots()
    _panel(ax, result, "L0: test", [], Normalize(0.0, 40.0), points_per_m=20.0)
    labels = [c.get_label() for c in ax.collections]
    assert "never unique (most headings)" in labels and "door" in labels
    never = next(c for c in ax.collections if c.get_label().startswith("never"))
    assert len(never.get_offsets()) == len(result.plan.positions)  # no start ever becomes unique
    assert len(ax.lines) == len(result.plan.occluders)
    assert ax.get_title() == "L0: test"
    plt.close(fig)


def test_survey_png_one_panel_then_two_with_landmarks(surveyed, tmp_path: Path) -> None:
    result, views = surveyed
    single = tmp_path / "survey_L0.png"
    survey_png(single, result)
    landmarks, after = suggest_landmarks(result, views, 1)
    double = tmp_path / "survey_L0_landmarks.png"
    survey_png(double, result, after, landmarks)
    (w1, h1), (w2, h2) = _png_size(single), _png_size(double)
    assert w1 > h1  # the 8 m x 5 m room: a wide panel
    assert h2 > 1.5 * h1 and w2 < 1.5 * w1  # a wide floor's two panels one above the other
    assert not list(tmp_path.glob(".*"))  # written atomically, no temporary left
