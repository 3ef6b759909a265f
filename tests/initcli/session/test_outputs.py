"""initcli.session.outputs: summary.json's document and the report.png of a session."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from bimtools.site.load import StoreyModel
from bimtools.site.records import Feature, WallSegment
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.geometry.se2 import Pose2D
from initcli.session.outputs import _ellipse, render_report, summary_document, write_summary
from initcli.session.result import MatchStep, SessionResult


def _result() -> SessionResult:
    return SessionResult(
        True,
        "converged",
        "L0",
        pose=Pose2D(1.234567, 2.0, math.pi / 2),
        covariance=np.diag([0.0123456789, 0.02, 0.001]),
        coarse_pose=Pose2D(1.5, 2.0, math.pi / 2),
        features_detected=5,
        matched_ids=["d1", None],
        distance_coarse_m=4.5,
        distance_total_m=10.12345,
        duration_s=33.333,
        wall_seconds=1.239,
        truth_pose=Pose2D(1.0, 2.0, math.pi / 2),
        truth_at_coarse=Pose2D(1.0, 2.0, math.pi / 2),
        transform=Pose2D(0.5, 0.0, 0.0),
        true_path=[(0.0, 0.0, 0.0), (1.0, 2.0, math.pi / 2)],
        odom_path=[(-0.5, 0.0, 0.0), (0.5, 2.0, math.pi / 2)],
        features=[
            ConfirmedFeature(0, "door", 2.5, 0.0, 3, 1.0, 2.0),
            ConfirmedFeature(1, "lift", 0.0, 3.0, 3, 1, 2),
        ],
        match_steps=[MatchStep(5.0, 2, "ambiguous", [(1.5, 2.0, 1.57), (8.0, 1.0, 0.0)])],
    )


def test_summary_document_rounds_and_reports_errors_when_simulated() -> None:
    doc = summary_document(_result(), simulated=True, extra={"seed": 7})
    assert doc["success"] is True and doc["reason"] == "converged" and doc["storey"] == "L0"
    assert doc["pose"] == {"x": 1.2346, "y": 2.0, "yaw": round(math.pi / 2, 5), "yaw_deg": 90.0}
    assert doc["covariance"][0] == [0.012346, 0.0, 0.0]
    assert doc["rectified_pose"] is None
    assert doc["distance_total_m"] == 10.123 and doc["duration_s"] == 33.33 and doc["wall_clock_s"] == 1.24
    assert doc["matched_ids"] == ["d1", None]
    assert doc["truth_pose"]["x"] == 1.0
    assert doc["error_translation_m"] == {"coarse": 0.5, "rectified": None, "fine": 0.2346}
    assert doc["seed"] == 7
    json.dumps(doc)


def test_summary_document_of_a_real_run_has_no_truth() -> None:
    result = _result()
    result.covariance = None
    doc = summary_document(result, simulated=False)
    assert doc["covariance"] is None
    assert not {"truth_pose", "error_translation_m", "error_rotation_deg"} & doc.keys()


def test_write_summary_round_trips(tmp_path: Path) -> None:
    path = tmp_path / "summary.json"
    doc = summary_document(_result(), simulated=True)
    write_summary(path, doc)
    assert json.loads(path.read_text()) == doc
    assert path.read_text().endswith("}\n")


def test_ellipse_axes_are_scaled_sigmas() -> None:
    ring = _ellipse(np.diag([4.0, 1.0, 9.0]))  # yaw variance ignored
    assert ring.shape == (60, 2)
    assert np.abs(ring[:, 0]).max() == pytest.approx(4.0, rel=1e-3)  # 2 sigma of x
    assert np.abs(ring[:, 1]).max() == pytest.approx(2.0, rel=1e-2)
    rotated = _ellipse(
        np.array([[2.5, 1.5], [1.5, 2.5]]), scale=1.0
    )  # eigenvalues 4 and 1 along the diagonals
    radii = np.hypot(*rotated.T)
    assert radii.max() == pytest.approx(2.0, rel=1e-2) and radii.min() == pytest.approx(1.0, rel=1e-2)


def test_render_report_writes_a_png(tmp_path: Path) -> None:
    storey = StoreyModel(
        "L0",
        0.0,
        [
            Feature("d1", "Door", 3.0, 0.0, -1.0, 0.0, 1.0, 2.1),
            Feature("l1", "Lift", 0.0, 4.0, 0.0, -1.0, 1.2, 2.2),
        ],
        [WallSegment("L0", "w", "IfcWall", 0.0, -1.0, 6.0, -1.0, (0.0, 1.0))],
    )
    out = tmp_path / "report.png"
    render_report(out, _result(), storey, "a title")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 10_000


def test_report_title_says_what_decided_the_pose_and_its_error_beside_its_sigma() -> None:
    from initcli.session.outputs import report_title
    from initcli.session.result import DecidedBy

    result = _result()
    result.decided_by = DecidedBy.REGISTRATION
    first, second = report_title(result, "block_b").split("\n")
    assert first == "block_b, storey L0: initialised - converged"
    assert second == "decided by lidar registration after 4.5 m; final error 0.23 m, 0.0 deg; sigma 0.14 m"
    failed = SessionResult(False, "max distance reached", None)
    assert report_title(failed, "x") == "x: not initialised - max distance reached"
    assert report_title(SessionResult(True, "initialised", None), "x") == "x: initialised"  # said once


def test_the_plan_is_cropped_to_the_building_not_to_a_hypothesis_far_outside() -> None:
    from initcli.session.outputs import PLAN_MARGIN_M, _plan_limits

    storey = StoreyModel("L0", 0.0, [], [WallSegment("L0", "w", "IfcWall", 0.0, -1.0, 6.0, -1.0, (0.0, 1.0))])
    result = _result()
    result.match_steps = [MatchStep(5.0, 2, "ambiguous", [(120.0, -80.0, 0.0)])]
    (x0, x1), (y0, y1) = _plan_limits(storey, result) or ((0, 0), (0, 0))
    assert (x0, x1) == (-PLAN_MARGIN_M, 6.0 + PLAN_MARGIN_M)
    assert (y0, y1) == (-1.0 - PLAN_MARGIN_M, 2.0 + PLAN_MARGIN_M)  # the true path ends at y 2


def test_beside_a_plan_wider_than_tall_the_inset_sits_under_the_legend(tmp_path: Path, monkeypatch) -> None:
    import matplotlib.pyplot as plt

    closed: list = []
    monkeypatch.setattr(plt, "close", closed.append)  # keep the figure to look at
    walls = [
        WallSegment("L0", f"w{i}", "IfcWall", *ends, (0.0, 1.0))
        for i, ends in enumerate([(0, 0, 60, 0), (60, 0, 60, 8), (60, 8, 0, 8), (0, 8, 0, 0)])
    ]
    storey = StoreyModel("L0", 0.0, [Feature("d1", "Door", 3.0, 0.0, -1.0, 0.0, 1.0, 2.1)], walls)
    render_report(tmp_path / "report.png", _result(), storey, "a title")
    (fig,) = closed
    ax = fig.axes[0]
    (inset,) = ax.child_axes
    legend = ax.get_legend()
    assert len(legend.get_texts()) >= 8  # tall beside this plan: it reaches below the middle
    box, zoom = legend.get_window_extent(), inset.get_tightbbox()
    assert not box.overlaps(zoom), (box, zoom)
    plt.close(fig)
