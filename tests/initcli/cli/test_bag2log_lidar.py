"""bim-init bag2log and match on inputs without a camera: a lidar-only bag and a CARMEN laser log
(gzipped); the summary line, the log's meta and match --json say the camera was absent."""

from __future__ import annotations

import gzip
import json

from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.io.detection_log import read_log
from tests.initcli.io.test_carmen import _flaser
from tests.initcli.ros.test_lidar_bag import _messages, _write

runner = CliRunner()


def test_bag2log_of_a_lidar_only_bag(tmp_path):
    bag = _write(tmp_path, "sqlite3", _messages(seconds=2.0))
    out = tmp_path / "log.jsonl"
    result = runner.invoke(app, ["bag2log", str(bag), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "camera absent (lidar only)" in result.stdout and "20 scans" in result.stdout
    log = read_log(out)
    assert log.meta.camera_absent and not log.detections and len(log.odom) == 40


def test_bag2log_of_a_carmen_log(tmp_path):
    path = tmp_path / "run.log.gz"
    text = _flaser(stamps=[3.0, 0.0] + [4.0 + i for i in range(18)])
    path.write_bytes(gzip.compress(text.encode()))
    out = tmp_path / "log.jsonl"
    result = runner.invoke(app, ["bag2log", str(path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "camera absent (lidar only)" in result.stdout and "20 scans" in result.stdout
    assert "made increasing" in result.stderr  # the one note on the stamps
    assert json.loads(out.read_text().splitlines()[0])["camera_absent"] is True


def test_bag2log_bad_carmen_line_is_one_line(tmp_path):
    path = tmp_path / "run.clf"
    path.write_text(_flaser(k=3).replace("FLASER 180", "FLASER 0", 1))
    result = runner.invoke(app, ["bag2log", str(path), "-o", str(tmp_path / "x.jsonl")])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "run.clf:4: FLASER: 0 ranges" in lines[0]
    assert not (tmp_path / "x.jsonl").exists()


def test_match_json_says_the_camera_was_absent(tmp_path, site_a):
    path = tmp_path / "run.log"
    path.write_text(_flaser())
    result = runner.invoke(app, ["match", str(path), "--site", str(site_a), "--json"])
    assert result.exit_code in (0, 3, 4), result.output
    assert json.loads(result.stdout)["camera_absent"] is True


def test_bag2log_never_writes_over_a_file_it_did_not_write(tmp_path):
    """-o onto a user's IFC model or a site's features.csv is refused and the file kept; onto a
    detection log an earlier run wrote it is written again."""
    path = tmp_path / "run.log"
    path.write_text(_flaser(stamps=[1.0 + i for i in range(20)]))
    model = tmp_path / "model.ifc"
    model.write_text("ISO-10303-21;\nHEADER;\n")
    features = tmp_path / "site" / "features.csv"
    features.parent.mkdir()
    features.write_text("ID,Category,X,Y\n")
    for target in (model, features):
        before = target.read_bytes()
        result = runner.invoke(app, ["bag2log", str(path), "-o", str(target)])
        assert result.exit_code == 2, result.output
        assert "is not a detection log this tool wrote" in result.stderr
        assert len(result.stderr.strip().splitlines()) == 1
        assert target.read_bytes() == before
    out = tmp_path / "log.jsonl"
    for _ in range(2):  # the second run writes over the first's log
        result = runner.invoke(app, ["bag2log", str(path), "-o", str(out)])
        assert result.exit_code == 0, result.output
