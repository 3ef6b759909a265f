"""bimtools.ifc.model: opening IFC files (every failure one InputError) and describing them."""

from __future__ import annotations

import hashlib
from pathlib import Path

import ifcopenshell
import ifcopenshell.api.root
import ifcopenshell.api.unit
import pytest

from bimkit.errors import InputError
from bimtools.ifc.model import (
    authoring_application,
    describe_model,
    file_sha256,
    length_unit_name,
    open_model,
)
from tests.helpers import SAMPLES

BLOCK_A = SAMPLES / "block_a.ifc"


def test_open_and_describe_a_sample() -> None:
    model = open_model(BLOCK_A)
    info = describe_model(BLOCK_A, model)
    assert info.schema == "IFC4"
    assert info.application == "bimtools.samples"
    assert info.length_unit == "METRE"
    assert info.unit_scale == pytest.approx(1.0)
    assert info.sha256 == hashlib.sha256(BLOCK_A.read_bytes()).hexdigest()
    assert info.path == BLOCK_A


def test_file_sha256_reads_in_blocks(tmp_path: Path) -> None:
    data = bytes(range(256)) * 9000  # > 1 MiB: more than one block
    path = tmp_path / "big.bin"
    path.write_bytes(data)
    assert file_sha256(path) == hashlib.sha256(data).hexdigest()


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"hello world\n", "not an IFC file"),
        (
            b"ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('IFC4'));\nENDSEC;\nDATA;\n#1=IFCWALL(",
            "truncated IFC file",
        ),
    ],
)
def test_open_model_refuses_non_ifc_and_truncated_files(tmp_path: Path, content: bytes, message: str) -> None:
    path = tmp_path / "bad.ifc"
    path.write_bytes(content)
    with pytest.raises(InputError, match=message):
        open_model(path)


def test_open_model_refuses_missing_paths_and_folders(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        open_model(tmp_path / "missing.ifc")
    with pytest.raises(InputError, match="is a folder"):
        open_model(tmp_path)


def test_open_model_refuses_a_file_without_a_project(tmp_path: Path) -> None:
    model = ifcopenshell.file(schema="IFC4")
    ifcopenshell.api.root.create_entity(model, ifc_class="IfcWall")
    path = tmp_path / "noproject.ifc"
    model.write(str(path))
    with pytest.raises(InputError, match="no IfcProject"):
        open_model(path)


def test_open_model_turns_parse_errors_into_one_line(tmp_path: Path) -> None:
    text = BLOCK_A.read_text(encoding="utf-8").replace("FILE_SCHEMA(('IFC4'))", "FILE_SCHEMA(('IFC9'))")
    path = tmp_path / "ifc9.ifc"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputError) as caught:
        open_model(path)
    assert "\n" not in str(caught.value)
    assert str(path) in str(caught.value)


def test_length_unit_and_application_of_a_millimetre_model() -> None:
    model = ifcopenshell.file(schema="IFC4")
    ifcopenshell.api.root.create_entity(model, ifc_class="IfcProject", name="P")
    assert length_unit_name(model) == "METRE"  # no units assigned
    mm = ifcopenshell.api.unit.add_si_unit(model, unit_type="LENGTHUNIT", prefix="MILLI")
    ifcopenshell.api.unit.assign_unit(model, units=[mm])
    assert length_unit_name(model) == "MILLIMETRE"
    assert authoring_application(model) in ("", str(model.header.file_name.originating_system or ""))
    model.createIfcApplication(None, "1.0", "My CAD", "mycad")
    assert authoring_application(model) == "My CAD"
