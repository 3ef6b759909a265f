"""bim-extract walks a list of bad inputs: exit 2, one line on stderr, no traceback, nothing left."""

from __future__ import annotations

import os
from pathlib import Path

import ifcopenshell
import ifcopenshell.api.aggregate
import ifcopenshell.api.root
import pytest
from typer.testing import CliRunner

from bimtools.cli import app
from tests.helpers import SAMPLES

runner = CliRunner()
MODEL = str(SAMPLES / "ntu_hallway.ifc")
BINARY = bytes(range(256)) * 4


def edited_model(target: Path, elevation: float | None = None, mezzanine: float | None = None) -> Path:
    """The hallway model with its storey raised to ``elevation``, or an empty storey ``mezzanine`` m
    above its floor (which makes the hallway's storey that high)."""
    model = ifcopenshell.open(MODEL)
    (storey,) = model.by_type("IfcBuildingStorey")
    if elevation is not None:
        storey.Elevation = elevation
    if mezzanine is not None:
        upper = ifcopenshell.api.root.create_entity(model, ifc_class="IfcBuildingStorey", name="Mezzanine")
        upper.Elevation = mezzanine
        ifcopenshell.api.aggregate.assign_object(
            model, products=[upper], relating_object=model.by_type("IfcBuilding")[0]
        )
    model.write(str(target))
    return target


def snapshot(root: Path) -> dict[str, int]:
    return {str(p.relative_to(root)): p.stat().st_size for p in root.rglob("*") if p.is_file()}


@pytest.fixture()
def work(tmp_path: Path) -> Path:
    (tmp_path / "binary.yaml").write_bytes(BINARY)
    (tmp_path / "latin1.yaml").write_bytes("categories:\n  - name: Caf\xe9\n".encode("latin-1"))
    (tmp_path / "nan.yaml").write_text(
        "categories:\n  - name: Doors\n    doors: [{classes: [IfcDoor]}]\n    enclosure_max_area: .nan\n"
    )
    door = "categories:\n  - name: Door\n    doors: [{classes: [IfcDoor]}]\n"
    (tmp_path / "angle.yaml").write_text(door + "landmarks: {corner_angle: [0, 90]}\n")
    (tmp_path / "lmkey.yaml").write_text(door + "landmarks: {enabled: true, min_legs: 0.3}\n")
    (tmp_path / "lmon.yaml").write_text(door + "landmarks: {enabled: 'yes'}\n")
    (tmp_path / "widths.yaml").write_text(door + "landmarks: {opening_width: [2.5, 0.7]}\n")
    (tmp_path / "reserved.yaml").write_text(
        "categories:\n  - name: Opening\n    doors: [{classes: [IfcDoor]}]\n"
    )
    (tmp_path / "afile").write_text("x\n")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("someone else's\n")
    (tmp_path / "model.ifc").write_bytes(BINARY)
    edited_model(tmp_path / "far.ifc", elevation=1e9)
    edited_model(tmp_path / "deep.ifc", elevation=-20000.0)
    return tmp_path


CASES = [
    ("--resolution nan", [MODEL, "--resolution", "nan"], "--resolution: nan is not a finite number"),
    ("--resolution 1e-9", [MODEL, "--resolution", "1e-9"], "--resolution: 1e-09 is below the minimum 0.005"),
    ("--resolution inf", [MODEL, "--resolution", "inf"], "--resolution"),
    ("--resolution 5", [MODEL, "--resolution", "5"], "is above the maximum 1"),
    (
        "--section-height 1e308",
        [MODEL, "--section-height", "1e308"],
        "--section-height: 1e+308 is above the maximum 10",
    ),
    ("--section-height -1", [MODEL, "--section-height", "-1"], "--section-height: -1 must be > 0"),
    ("--section-height nan", [MODEL, "--section-height", "nan"], "--section-height"),
    ("binary --categories", [MODEL, "--categories", "binary.yaml", "-o", "out"], "not a text file"),
    ("latin-1 --categories", [MODEL, "--categories", "latin1.yaml", "-o", "out"], "not UTF-8"),
    ("--categories nan area", [MODEL, "--categories", "nan.yaml", "-o", "out"], "nan is not a finite number"),
    ("--categories a folder", [MODEL, "--categories", "other", "-o", "out"], "is a folder"),
    (
        "landmarks corner_angle 0",
        [MODEL, "--categories", "angle.yaml", "-o", "out"],
        "angle.yaml: landmarks.corner_angle[0]: 0 must be > 0",
    ),
    ("landmarks unknown key", [MODEL, "--categories", "lmkey.yaml", "-o", "out"], "unknown key(s) min_legs"),
    (
        "landmarks enabled 'yes'",
        [MODEL, "--categories", "lmon.yaml", "-o", "out"],
        "enabled: expected true or false",
    ),
    (
        "landmarks widths reversed",
        [MODEL, "--categories", "widths.yaml", "-o", "out"],
        "low 2.5 is above high 0.7",
    ),
    (
        "reserved category name",
        [MODEL, "--categories", "reserved.yaml", "-o", "out"],
        "is a lidar landmark category",
    ),
    ("-o a file", [MODEL, "-o", "afile"], "-o/--outdir afile: is a file"),
    ("-o under a file", [MODEL, "-o", "afile/site"], "is a file"),
    ("-o foreign folder", [MODEL, "-o", "other"], "pass --force"),
    ("binary model", ["model.ifc", "-o", "out"], "model.ifc"),
    (
        "storey elevation 1e9",
        ["far.ifc", "-o", "out"],
        "far.ifc: storey 'Level 1' has an elevation of 1e+09 m, beyond +-10 km",
    ),
    ("storey elevation -20 km", ["deep.ifc", "-o", "out"], "storey 'Level 1' has an elevation of -20000 m"),
    (
        "--section-height above every wall",
        [MODEL, "--section-height", "10", "-o", "out"],
        "--section-height 10 m cuts no wall on any storey (the lowest storey is 3.00 m high)",
    ),
    ("missing model", ["missing.ifc", "-o", "out"], "missing.ifc"),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_extract_refuses_bad_input(work: Path, case) -> None:
    _, args, fragment = case
    before = snapshot(work)
    here = os.getcwd()
    os.chdir(work)
    try:
        result = runner.invoke(app, args)
    finally:
        os.chdir(here)
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.exit_code == 2, (args, result.output)
    assert len(lines) == 1 and lines[0].startswith("bim-extract: error: "), result.stderr
    assert fragment in lines[0], lines[0]
    assert "Traceback" not in result.output
    assert snapshot(work) == before
    assert not [p for p in work.iterdir() if p.name.startswith(".")]


def test_an_earlier_site_folder_gets_the_new_site_and_keeps_what_it_did_not_write(work: Path) -> None:
    out = work / "site"
    out.mkdir()
    (out / "site.json").write_text("{}")
    (out / "features.csv").write_text("ID,old\n")
    (out / "stale.txt").write_text("from an older run, or the user's")
    result = runner.invoke(app, [MODEL, "-o", str(out), "--json"])
    assert result.exit_code == 0, result.output
    assert (out / "features.csv").read_text().startswith("ID,Category")  # replaced: bim-extract wrote it
    assert (out / "stale.txt").read_text() == "from an older run, or the user's"  # kept
    assert sorted(p.name for p in work.iterdir() if p.name.startswith(".")) == []
    result = runner.invoke(app, [MODEL, "-o", str(out), "--json"])  # again: from the record, no --force
    assert result.exit_code == 0, result.output
    assert (out / "stale.txt").is_file()


def test_force_writes_into_a_foreign_folder_and_keeps_its_files(work: Path) -> None:
    result = runner.invoke(app, [MODEL, "-o", str(work / "other"), "--force", "--json"])
    assert result.exit_code == 0, result.output
    assert (work / "other" / "site.json").is_file() and (work / "other" / "notes.txt").is_file()


def test_a_section_height_above_a_storeys_height_is_a_warning_naming_the_storey(tmp_path: Path) -> None:
    model = edited_model(tmp_path / "mezz.ifc", mezzanine=1.5)  # Level 1 is 1.5 m high, its walls 3 m
    result = runner.invoke(app, [str(model), "-o", str(tmp_path / "out"), "--section-height", "2", "--json"])
    assert result.exit_code == 0, result.output
    warnings = [line for line in result.stderr.splitlines() if "warning" in line]
    assert len(warnings) == 2, result.stderr  # the mezzanine is 1.5 m high too: up to the walls' top
    assert "storey 'Level 1': the section height 2 m is above the storey's height (1.50 m)" in warnings[0]
    assert "storey 'Mezzanine'" in warnings[1] and "its plan has 0 walls" in warnings[1]
    result = runner.invoke(app, [str(model), "-o", str(tmp_path / "out2"), "--json"])  # 1 m: below
    assert result.exit_code == 0 and "warning" not in result.stderr, result.stderr
