"""``bim-init survey`` end to end on the block_b sample: survey.json (valid against its schema), the
map, landmarks that do not lengthen the mean distance, and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
from typer.testing import CliRunner

from bimkit.schemas import schema_path
from initcli.cli.main import app
from initcli.config import load_config
from initcli.config.building import prepare_site

SAMPLES = Path(__file__).resolve().parents[3] / "sample_models"
runner = CliRunner()


@pytest.fixture(scope="module")
def site_dir(tmp_path_factory) -> Path:
    site = prepare_site(load_config(SAMPLES / "block_b.site.yaml"), tmp_path_factory.mktemp("survey"))
    return Path(site.root)


def test_survey_writes_a_valid_report_and_a_map(site_dir, tmp_path):
    out = tmp_path / "out"
    args = [
        "survey",
        str(site_dir),
        "--out",
        str(out),
        "--spacing",
        "2",
        "--headings",
        "2",
        "--landmarks",
        "1",
    ]
    result = runner.invoke(app, [*args, "--workers", "1"])
    assert result.exit_code == 0, result.output
    report = json.loads((out / "survey.json").read_text())
    jsonschema.validate(report, json.loads(schema_path("survey.schema.json").read_text()))
    (storey,) = report["storeys"]
    assert storey["samples"] == 2 * storey["positions"] > 10
    shares = storey["unique_within"]
    assert 0 <= shares["5m"] <= shares["10m"] <= shares["20m"] <= 1
    assert (out / storey["map"]).stat().st_size > 10_000
    (landmark,) = storey["landmarks"]
    before = storey["mean_distance_m"]
    assert landmark["category"] == "landmark_1"
    assert storey["with_landmarks"]["unique_within"]["20m"] >= shares["20m"] - 1e-9 or before is None
    assert "Survey" in result.output


def test_as_built_a_match_may_hold_one_outlier_more_and_is_unique_no_sooner(site_dir, tmp_path):
    reports = {}
    camera_only = tmp_path / "camera.yaml"  # the lidar's registration is the same either way
    camera_only.write_text(f"site: {{path: {site_dir}}}\nregistration: {{enabled: false}}\n")
    for reality in ("ideal", "construction"):
        out = tmp_path / reality
        args = ["survey", str(site_dir), "--out", str(out), "--spacing", "2", "--headings", "2"]
        args += ["--config", str(camera_only), "--reality", reality]
        result = runner.invoke(app, [*args, "--landmarks", "0", "--workers", "1"])
        assert result.exit_code == 0, result.output
        reports[reality] = json.loads((out / "survey.json").read_text())
        jsonschema.validate(reports[reality], json.loads(schema_path("survey.schema.json").read_text()))
    ideal, built = reports["ideal"], reports["construction"]
    assert (ideal["reality"], built["reality"]) == ("ideal", "construction")
    assert built["max_outliers"] == ideal["max_outliers"] + 1
    (a,), (b,) = ideal["storeys"], built["storeys"]
    assert b["samples"] == a["samples"]
    for within in ("5m", "10m", "20m"):
        assert b["unique_within"][within] <= a["unique_within"][within]
    assert b["unique_within"]["5m"] < a["unique_within"]["5m"]  # block_b's repeating offices


def test_unknown_storey_and_executor_exit_2(site_dir, tmp_path):
    for extra in (["--storey", "Roof"], ["--executor", "slurm"], ["--reality", "rubble"]):
        result = runner.invoke(app, ["survey", str(site_dir), "--out", str(tmp_path), *extra])
        assert result.exit_code == 2
        assert result.output.count("\n") <= 2 and "error" in result.output


def test_a_full_disk_mid_way_leaves_no_map_and_no_folder(site_dir, tmp_path, monkeypatch):
    """The disk fills while the map is written: the folder the survey made goes with what it had
    begun to write, and the error goes on to the command's one line (``run_cli``)."""
    import errno

    import initcli.survey.plots as plots

    def full(path: Path, *args: object) -> None:
        path.write_bytes(b"\x89PNG half")  # the part that fitted
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(plots, "survey_png", full)
    out = tmp_path / "new" / "out"
    result = runner.invoke(
        app,
        ["survey", str(site_dir), "--out", str(out), "--spacing", "5", "--headings", "1", "--workers", "1"],
    )
    assert isinstance(result.exception, OSError) and result.exception.errno == errno.ENOSPC
    assert not out.exists()
    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / "notes.txt").write_text("mine")
    result = runner.invoke(
        app,
        [
            "survey",
            str(site_dir),
            "--out",
            str(kept),
            "--spacing",
            "5",
            "--headings",
            "1",
            "--workers",
            "1",
            "--force",
        ],
    )
    assert isinstance(result.exception, OSError)
    assert sorted(p.name for p in kept.iterdir()) == ["notes.txt"]
    assert (kept / "notes.txt").read_text() == "mine"


def test_a_site_without_any_map_is_refused_not_surveyed_empty(site_dir, tmp_path):
    import shutil

    bare = tmp_path / "bare"
    bare.mkdir()
    shutil.copy(site_dir / "features.csv", bare / "features.csv")  # no site.json, no maps
    out = tmp_path / "out"
    result = runner.invoke(app, ["survey", str(bare), "--out", str(out), "--workers", "1"])
    assert result.exit_code == 2
    assert "no storey with an occupancy map to survey" in " ".join(result.output.split())
    assert not out.exists()
