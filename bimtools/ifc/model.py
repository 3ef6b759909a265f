"""Open an IFC file and describe it (schema, authoring application, length unit)."""

from __future__ import annotations

import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import ifcopenshell
import ifcopenshell.util.unit

from bimkit.documents import file_sha256, open_input
from bimkit.errors import InputError
from bimkit.limits import MAX_IFC_BYTES

__all__ = [
    "ModelInfo",
    "SUPPORTED_SCHEMAS",
    "authoring_application",
    "describe_model",
    "file_sha256",
    "length_unit_name",
    "open_model",
]

SUPPORTED_SCHEMAS = ("IFC2X3", "IFC4", "IFC4X3")
HEADER_BYTES = 65536  # the HEADER section is read this far for its FILE_SCHEMA before parsing
_FILE_SCHEMA = re.compile(rb"FILE_SCHEMA\s*\(\s*\(\s*'([^']*)'")


@dataclass(frozen=True)
class ModelInfo:
    path: Path
    sha256: str
    schema: str
    application: str
    length_unit: str
    unit_scale: float  # project length unit -> metres


def _parse(path: Path) -> ifcopenshell.file:
    """``ifcopenshell.open``; a file name that is not UTF-8 (Latin-1 bytes from an old archive) is
    opened through a link with a plain name, which ifcopenshell's C++ side can take."""
    try:
        os.fsencode(path).decode("utf-8")
    except UnicodeDecodeError:
        with tempfile.TemporaryDirectory(prefix="bim-extract-") as tmp:
            link = Path(tmp) / "model.ifc"
            os.symlink(os.path.abspath(path), link)
            return ifcopenshell.open(str(link))
    return ifcopenshell.open(str(path))


def _check_header_schema(path: Path, head: bytes) -> None:
    """The FILE_SCHEMA the header names, before IfcOpenShell parses anything: it crashes (a
    segmentation fault) on some names no schema has, so an unknown one is refused here."""
    found = _FILE_SCHEMA.search(head.split(b"ENDSEC;", 1)[0])
    if found is None:
        raise InputError(f"{path}: no FILE_SCHEMA in the IFC header")
    _check_schema(path, found.group(1).decode("latin-1").strip())


def _check_schema(path: Path, name: str) -> None:
    """The one rule on a schema name, the header's before parsing and the model's after."""
    if not any(name.upper().startswith(s) for s in SUPPORTED_SCHEMAS):
        shown = name if len(name) <= 20 else name[:17] + "..."
        raise InputError(
            f"{path}: unsupported IFC schema {shown!r}; supported: {', '.join(SUPPORTED_SCHEMAS)}"
        )


def _probe_header(path: Path, head: bytes) -> None:
    """IfcOpenShell crashes (a segmentation fault) on some malformed HEADER sections (found by the
    fuzz suite): the header alone, with an empty DATA section, is parsed in a forked child first,
    and a crash there is one line here. Errors other than a crash are left to the real parse."""
    if not hasattr(os, "fork"):
        return
    header = head.split(b"ENDSEC;", 1)[0] + b"ENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n"
    with tempfile.TemporaryDirectory(prefix="bim-extract-") as tmp:
        probe = Path(tmp) / "header.ifc"
        probe.write_bytes(header)
        pid = os.fork()
        if pid == 0:  # the child: parse, and leave without running any of the parent's clean-up
            code = 0
            try:
                os.dup2(os.open(os.devnull, os.O_WRONLY), 2)
                ifcopenshell.open(str(probe))
            except BaseException:  # noqa: BLE001 - the real parse says what is wrong
                code = 1
            os._exit(code)
        _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        raise InputError(f"{path}: malformed IFC header (IfcOpenShell crashes reading it)")


def open_model(path: Path) -> ifcopenshell.file:
    """Open an IFC-SPF file, turning every failure into one :class:`InputError` line."""
    path = Path(path)
    if not os.path.lexists(path):
        raise InputError(f"{path}: no such file")
    if path.is_dir():
        raise InputError(f"{path}: is a folder, expected an .ifc file")
    with os.fdopen(open_input(path, "an IFC model", MAX_IFC_BYTES), "rb") as handle:
        head = handle.read(HEADER_BYTES)
        handle.seek(0, 2)
        size = handle.tell()
        handle.seek(max(0, size - 1024))
        tail = handle.read()
    if not head.lstrip().startswith(b"ISO-10303-21"):
        raise InputError(f"{path}: not an IFC file (no ISO-10303-21 header)")
    if b"END-ISO-10303-21" not in tail:
        raise InputError(f"{path}: truncated IFC file (no END-ISO-10303-21 at the end)")
    _check_header_schema(path, head)
    _probe_header(path, head)
    try:
        model = _parse(path)
    except Exception as exc:  # ifcopenshell raises a variety of types for parse errors
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        if "schema" in text.lower():
            raise InputError(f"{path}: unsupported IFC schema ({text})") from None
        raise InputError(f"{path}: cannot parse IFC file ({text}); is it truncated?") from None
    _check_schema(path, str(model.schema_identifier if hasattr(model, "schema_identifier") else model.schema))
    if not model.by_type("IfcProject"):
        raise InputError(f"{path}: IFC file has no IfcProject; is it truncated?")
    return model


def authoring_application(model: ifcopenshell.file) -> str:
    apps = [a.ApplicationFullName for a in model.by_type("IfcApplication") if a.ApplicationFullName]
    if apps:
        return apps[0]
    try:
        system = model.header.file_name.originating_system
    except (AttributeError, RuntimeError):
        system = ""
    return str(system or "")


def length_unit_name(model: ifcopenshell.file) -> str:
    for project in model.by_type("IfcProject"):
        assignment = project.UnitsInContext
        for unit in assignment.Units if assignment else []:
            if getattr(unit, "UnitType", None) != "LENGTHUNIT":
                continue
            if unit.is_a("IfcSIUnit"):
                return f"{unit.Prefix or ''}{unit.Name}"
            return str(getattr(unit, "Name", "unknown")).upper()
    return "METRE"


def describe_model(path: Path, model: ifcopenshell.file) -> ModelInfo:
    return ModelInfo(
        path=Path(path),
        sha256=file_sha256(path),
        schema=str(model.schema),
        application=authoring_application(model),
        length_unit=length_unit_name(model),
        unit_scale=float(ifcopenshell.util.unit.calculate_unit_scale(model)),
    )
