"""The match-result JSON document (initcli.match.report_file) against its schema."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np

from initcli.cli.exit_codes import match_exit_code
from initcli.core.geometry.se2 import MATCH_DIGITS, SESSION_DIGITS, Pose2D, pose_json
from initcli.io.log_writer import write_log
from initcli.match.pipeline import MatchOptions, run_match
from initcli.match.report_file import RESULT_FORMAT, report_to_dict
from initcli.sim.synthetic_floor import write_site_folder
from initcli.sim.synthetic_log import SimFeature, make_log, path_from_waypoints
from tests.helpers import ROOT


def test_report_to_dict_follows_the_schema_and_carries_the_verdict(tmp_path: Path) -> None:
    doors = [SimFeature(f"D{i}", "door", x, 1.0, 0.0, -1.0) for i, x in enumerate((3.0, 7.5, 13.0, 16.0))]
    walls = np.array([[0.0, -1.0, 20.0, -1.0, 0.0, 1.0], [0.0, 1.0, 20.0, 1.0, 0.0, -1.0]])
    site = write_site_folder(tmp_path / "site", {"L1": (doors, walls)})
    t, path = path_from_waypoints([(1.0, 0.0), (18.0, 0.0)], start_yaw=0.0)
    write_log(tmp_path / "log.jsonl", make_log(doors, t, path).records)
    report = run_match(tmp_path / "log.jsonl", site, MatchOptions())
    doc = report_to_dict(report, exit_code=match_exit_code(report.outcome))
    schema = json.loads((ROOT / "schemas" / "match_result.schema.json").read_text())
    jsonschema.validate(doc, schema)
    assert doc["format"] == RESULT_FORMAT
    assert doc["exit_code"] == match_exit_code(report.outcome)
    assert doc["verdict"] == report.verdict and doc["n_hypotheses"] == report.n_hypotheses
    assert len(doc["hypotheses"]) == len(report.hypotheses)
    assert all(h["verification"] is None for h in doc["hypotheses"])  # none asked for
    assert doc["parameters"]["beta_deg"] == MatchOptions().beta


def test_poses_are_written_with_the_document_s_rounding() -> None:
    """The match result's poses at MATCH_DIGITS, summary.json's at SESSION_DIGITS (one function)."""
    pose = Pose2D(1.23456789, -2.0000004, 0.123456789)
    assert pose_json(pose, MATCH_DIGITS) == {"x": 1.234568, "y": -2.0, "yaw": 0.123457, "yaw_deg": 7.0736}
    assert pose_json(pose, SESSION_DIGITS) == {"x": 1.2346, "y": -2.0, "yaw": 0.12346, "yaw_deg": 7.074}
