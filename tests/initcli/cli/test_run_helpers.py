"""initcli.cli.run called directly: parse_start, result_table, LiveView."""

from __future__ import annotations

import math

import pytest
from rich.console import Console
from rich.table import Table

from bimkit.errors import InputError
from initcli.cli.run import LiveView, parse_start, result_table


def _text(table: Table) -> str:
    console = Console(record=True, width=200, color_system=None)
    console.print(table)
    return console.export_text()


def test_parse_start_reads_degrees() -> None:
    pose = parse_start("12.5,-3,90")
    assert (pose.x, pose.y) == (12.5, -3.0)
    assert pose.yaw == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("text", ["1,2", "1,2,3,4", "a,b,c", "", "2e6,0,0", "0,0,4000", "nan,0,0", "0,inf,0"])
def test_parse_start_refuses_bad_text(text: str) -> None:
    with pytest.raises(InputError, match="--start"):
        parse_start(text)


def _doc(**over: object) -> dict:
    doc = {
        "success": True,
        "reason": "converged",
        "storey": "L1",
        "coarse_pose": {"x": 1.0, "y": 2.0, "yaw_deg": 3.0},
        "rectified_pose": None,
        "pose": {"x": 1.25, "y": 2.5, "yaw_deg": -45.5},
        "features_detected": 9,
        "distance_coarse_m": 12.3,
        "distance_total_m": 20.1,
        "duration_s": 55.0,
        "wall_clock_s": 4.2,
    }
    doc.update(over)
    return doc


def test_result_table_rows() -> None:
    text = _text(result_table(_doc()))
    assert "yes" in text and "converged" in text and "L1" in text
    assert "x 1.250  y 2.500  yaw -45.50 deg" in text
    rectified = next(line for line in text.splitlines() if "rectified pose" in line)
    assert rectified.split("rectified pose")[1].strip(" │|").strip() == "-"
    assert "12.3 m / 20.1 m" in text and "55.0 s (simulated in 4.2 s)" in text
    assert "error" not in text and "decided by" not in text
    registered = _text(result_table(_doc(decided_by="lidar registration")))
    assert "decided by" in registered and "lidar registration" in registered


def test_result_table_errors_and_failure() -> None:
    doc = _doc(
        success=False,
        error_translation_m={"coarse": 0.5, "rectified": None, "fine": 0.1234},
        error_rotation_deg={"coarse": 2.0, "rectified": None, "fine": 0.5},
    )
    text = _text(result_table(doc))
    assert "no" in text and "yes" not in text
    assert "0.500 m, 2.00 deg" in text and "0.123 m, 0.50 deg" in text
    rectified = next(line for line in text.splitlines() if "error rectified" in line)
    assert "-" in rectified.split("error rectified")[1]


def test_live_view_table_and_throttling() -> None:
    view = LiveView(Console(record=True, width=100, color_system=None))
    text = _text(
        view._table({"t": 3.25, "state": "matching", "distance": 4.0, "features": 2, "covariance": 0.04})
    )
    assert "3.2 s" in text  # one decimal
    assert "matching" in text and "4.0 m" in text and "0.200 m" in text
    assert "pose sigma" not in _text(view._table({}))
    assert "starting" in _text(view._table({}))
    view({"t": 1.0})
    first = view.last
    assert first > 0
    view({"t": 2.0})  # within 0.2 s: not redrawn
    assert view.last == first
