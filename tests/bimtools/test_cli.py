"""Every bad input to bim-extract: one line on stderr, exit code 2, no partial output."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import ifcopenshell
import ifcopenshell.api
import pytest

from tests.helpers import SAMPLES

MINIMAL_HEADER = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('ViewDefinition [CoordinationView]'),'2;1');
FILE_NAME('x.ifc','2026-01-01T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('{schema}'));
ENDSEC;
DATA;
#1=IFCPROJECT('0YvctVUKr0kugbFTf53O9L',$,'P',$,$,$,$,$,$);
ENDSEC;
END-ISO-10303-21;
"""


def run_extract(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", "from bimtools.cli import main; main()", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


def assert_bad_input(result: subprocess.CompletedProcess, *fragments: str) -> None:
    assert result.returncode == 2, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def model_without(tmp_path: Path, storeys: bool) -> Path:
    model = ifcopenshell.api.run("project.create_file", version="IFC4")
    project = ifcopenshell.api.run("root.create_entity", model, ifc_class="IfcProject", name="P")
    ifcopenshell.api.run("unit.assign_unit", model)
    site = ifcopenshell.api.run("root.create_entity", model, ifc_class="IfcSite", name="S")
    building = ifcopenshell.api.run("root.create_entity", model, ifc_class="IfcBuilding", name="B")
    ifcopenshell.api.run("aggregate.assign_object", model, relating_object=project, products=[site])
    ifcopenshell.api.run("aggregate.assign_object", model, relating_object=site, products=[building])
    if storeys:
        storey = ifcopenshell.api.run("root.create_entity", model, ifc_class="IfcBuildingStorey", name="L1")
        ifcopenshell.api.run("aggregate.assign_object", model, relating_object=building, products=[storey])
    path = tmp_path / ("empty_storey.ifc" if storeys else "no_storeys.ifc")
    model.write(str(path))
    return path


@pytest.fixture
def small_ifc(tmp_path) -> Path:
    source = SAMPLES / "block_a.ifc"
    if not source.exists():
        pytest.skip("sample_models/block_a.ifc not generated")
    return Path(shutil.copy(source, tmp_path / "block_a.ifc"))


def test_not_an_ifc_file(tmp_path):
    path = tmp_path / "notes.ifc"
    path.write_text("hello, this is not IFC\n")
    result = run_extract(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert_bad_input(result, "notes.ifc", "not an IFC file")
    assert not (tmp_path / "out").exists()


def test_missing_file(tmp_path):
    assert_bad_input(run_extract(str(tmp_path / "nope.ifc"), cwd=tmp_path), "nope.ifc", "no such file")


def test_truncated_file(tmp_path, small_ifc):
    data = small_ifc.read_bytes()
    small_ifc.write_bytes(data[: len(data) // 2])
    result = run_extract(str(small_ifc), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert_bad_input(result, "block_a.ifc", "truncated")
    assert not (tmp_path / "out").exists()


def test_unsupported_schema(tmp_path):
    path = tmp_path / "old.ifc"
    path.write_text(MINIMAL_HEADER.format(schema="IFC4X3_RC2"))
    assert_bad_input(run_extract(str(path), cwd=tmp_path), "old.ifc", "unsupported IFC schema")


def test_a_schema_name_no_ifc_has_is_refused_before_ifcopenshell_reads_it(tmp_path):
    """IfcOpenShell crashes (a segmentation fault) on some FILE_SCHEMA names, such as 10000 digits
    (found by the fuzz suite): the header is read first and an unknown schema refused."""
    path = tmp_path / "odd.ifc"
    path.write_text(MINIMAL_HEADER.format(schema="9" * 10000))
    assert_bad_input(run_extract(str(path), cwd=tmp_path), "odd.ifc", "unsupported IFC schema '99999")
    path.write_text(MINIMAL_HEADER.format(schema="IFC4").replace("FILE_SCHEMA", "FILE_SCHEME"))
    assert_bad_input(run_extract(str(path), cwd=tmp_path), "odd.ifc", "no FILE_SCHEMA in the IFC header")
    path.write_text(MINIMAL_HEADER.format(schema="IFC4").replace("'IFC4')", "'IFC4')1e300"))
    assert_bad_input(run_extract(str(path), cwd=tmp_path), "odd.ifc", "malformed IFC header")


def test_model_without_storeys(tmp_path):
    path = model_without(tmp_path, storeys=False)
    assert_bad_input(run_extract(str(path), cwd=tmp_path), "no_storeys.ifc", "no storeys")


def test_model_without_features(tmp_path):
    path = model_without(tmp_path, storeys=True)
    assert_bad_input(run_extract(str(path), cwd=tmp_path), "empty_storey.ifc", "no features")
    assert not list(tmp_path.glob("*_site"))


def test_a_storey_without_features_is_named(tmp_path):
    path = model_without(tmp_path, storeys=True)
    result = run_extract(str(path), "--storey", "L1", "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert_bad_input(result, "empty_storey.ifc", "no doors, lifts or stairs on storey 'L1'")
    assert not (tmp_path / "out").exists()


def test_unknown_storey_lists_valid_names(tmp_path, small_ifc):
    result = run_extract(str(small_ifc), "--storey", "Level 9", "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert_bad_input(result, "no storey 'Level 9'", "valid storeys: 'Level 1'")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("categories: [\n  - name: Door\n", "invalid YAML"),
        ("categories: []\n", "expected a non-empty list"),
        (
            "categories:\n  - name: Door\n    kind: window\n    doors: [{classes: [IfcDoor]}]\n",
            "kind: expected one of",
        ),
        (
            "categories:\n  - name: Door\n    doors: [{classes: [IfcDoor], text: '(['}]\n",
            "invalid regular expression",
        ),
        ("categories:\n  - name: Door\n    doors: [{klass: [IfcDoor]}]\n", "unknown key(s) klass"),
    ],
)
def test_invalid_categories_file(tmp_path, small_ifc, text, fragment):
    path = tmp_path / "cats.yaml"
    path.write_text(text)
    result = run_extract(str(small_ifc), "--categories", str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert_bad_input(result, "cats.yaml", fragment)
    assert not (tmp_path / "out").exists()


def test_failed_run_keeps_previous_output(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "features.csv").write_text("previous\n")
    (out / "site.json").write_text("{}\n")  # an earlier bim-extract run's folder
    path = tmp_path / "bad.ifc"
    path.write_text("garbage")
    assert_bad_input(run_extract(str(path), "-o", str(out), cwd=tmp_path), "bad.ifc")
    assert (out / "features.csv").read_text() == "previous\n"
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".out")] == []


def test_no_progress_bar_off_a_terminal(monkeypatch, capfd):
    """A log file (stderr not a terminal) gets no bar, and no stray newline when it stops."""
    import io

    from rich.console import Console

    import bimtools.cli
    from bimtools.cli import LazyProgress

    log = io.StringIO()
    monkeypatch.setattr(bimtools.cli, "err", Console(file=log, force_terminal=False))
    progress = LazyProgress("geometry", delay=0.0)
    progress(1, 2)
    progress(2, 2)
    progress.close()
    assert progress.progress is None
    assert log.getvalue() == "" and capfd.readouterr().err == ""
