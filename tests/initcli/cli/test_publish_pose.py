"""initcli.cli.publish_pose called directly with --dry-run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from initcli.cli.publish_pose import publish_pose


def test_publish_pose_dry_run_prints_the_message(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    summary = tmp_path / "summary.json"
    doc = {"success": True, "pose": {"x": 2.0, "y": 3.0, "yaw_deg": 180.0}, "duration_s": 7.5}
    doc["covariance"] = [[0.1, 0, 0], [0, 0.2, 0], [0, 0, 0.3]]
    summary.write_text(json.dumps(doc))
    publish_pose(summary, dry_run=True)
    out = capsys.readouterr().out
    msg = json.loads(out[: out.rindex("}") + 1])
    assert msg["header"]["stamp"] == {"sec": 7, "nanosec": 500_000_000}
    assert msg["pose"]["pose"]["position"] == {"x": 2.0, "y": 3.0, "z": 0.0}
    assert msg["pose"]["pose"]["orientation"]["w"] == pytest.approx(0.0, abs=1e-12)
    cov = msg["pose"]["covariance"]
    assert (cov[0], cov[7], cov[35]) == (0.1, 0.2, 0.3)


def test_publish_pose_failed_session_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import typer

    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"success": False, "reason": "distance limit"}))
    with pytest.raises(typer.Exit) as exc:
        publish_pose(summary, dry_run=True)
    assert exc.value.exit_code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "distance limit" in err
