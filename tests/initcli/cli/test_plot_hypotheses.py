"""initcli.cli.plot_hypotheses: the drawn extent and the PNG of the top hypotheses per storey."""

from __future__ import annotations

import struct
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from bimtools.site.load import StoreyModel
from bimtools.site.records import Feature, WallSegment
from initcli.cli.plot_hypotheses import _extent, plot_hypotheses
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.geometry.se2 import Pose2D


def _storey(name: str) -> StoreyModel:
    return StoreyModel(
        name,
        0.0,
        [
            Feature("d1", "Door", 0.0, 0.0, 0.0, 1.0, 1.0, 2.1),
            Feature("s1", "Stairs", 10.0, 0.0, 0.0, 1.0, 1.0, 2.1),
        ],
        [WallSegment(name, "w", "IfcWall", 0.0, -2.0, 10.0, -2.0, (0.0, 1.0))],
    )


def _hypothesis(storey: str, rank: int, transform: Pose2D) -> SimpleNamespace:
    return SimpleNamespace(
        storey=storey,
        rank=rank,
        cost=0.5,
        confidence=0.8,
        transform=transform,
        matches=["d1"],
        pose=transform,
        rectified_pose=None,
        reported_pose=transform,  # Hypothesis.reported_pose: the rectified pose, else the pose
    )


def _report(hypotheses: list, storeys: list[str], site: bool = True) -> SimpleNamespace:
    model = SimpleNamespace(storeys={s: _storey(s) for s in storeys}) if site else None
    return SimpleNamespace(
        site_model=model,
        hypotheses=hypotheses,
        storeys=storeys,
        odom_path=np.array([[0.0, 0.0, 0.0], [5.0, 3.0, 0.0]]),
        features=[ConfirmedFeature(0, "door", 0.5, 0.5, 3, 0.0, 1.0)],
        truth=Pose2D(1.0, 1.0, 0.0),
        verdict="ambiguous",
    )


def test_extent_spans_features_walls_and_mapped_paths_plus_margin() -> None:
    report = _report([_hypothesis("L0", 1, Pose2D(0, 0, 0))], ["L0"])
    assert _extent(report, ["L0"]) == pytest.approx((12.0, 7.0))  # x 0..10, y -2..3
    shifted = _report([_hypothesis("L0", 1, Pose2D(0.0, 5.0, 0.0))], ["L0"])
    assert _extent(shifted, ["L0"]) == pytest.approx((12.0, 12.0))  # path now up to y 8


def test_extent_of_nothing_is_one_by_one() -> None:
    assert _extent(_report([], [], site=False), []) == (1.0, 1.0)


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_plot_has_one_panel_per_storey_of_the_hypotheses(tmp_path: Path) -> None:
    one = _report(
        [_hypothesis("L0", 1, Pose2D(0, 0, 0)), _hypothesis("L0", 2, Pose2D(1, 0, 0.1))], ["L0", "L1"]
    )
    two = _report(
        [_hypothesis("L0", 1, Pose2D(0, 0, 0)), _hypothesis("L1", 2, Pose2D(1, 0, 0.1))], ["L0", "L1"]
    )
    a = plot_hypotheses(one, tmp_path / "new" / "a.png", dpi=40)
    b = plot_hypotheses(two, tmp_path / "b.png", dpi=40)
    assert a == tmp_path / "new" / "a.png"
    (wa, ha), (wb, hb) = _png_size(a), _png_size(b)
    assert wa == wb == 11 * 40
    assert hb == pytest.approx(2 * ha, abs=2)


def test_plot_without_hypotheses_draws_the_first_storey(tmp_path: Path) -> None:
    out = plot_hypotheses(_report([], ["L0", "L1"]), tmp_path / "c.png", dpi=40)
    assert _png_size(out)[0] == 11 * 40
