"""``site.json``: the manifest of a ``bim-extract`` OUTDIR."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from bimkit.checks import read_json
from bimkit.errors import InputError
from bimtools.settings import LandmarkSettings, parse_landmarks
from bimtools.site.records import StoreyInfo

__all__ = ["SITE_FORMAT", "SiteManifest", "format_manifest", "read_manifest"]

SITE_FORMAT = "bim-init.site/1"


@dataclass
class SiteManifest:
    source_file: str
    source_sha256: str
    schema: str  # the IFC schema of the source, e.g. IFC4
    application: str
    length_unit: str
    unit_scale: float
    section_height: float
    resolution: float
    storeys: list[StoreyInfo] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    tool_version: str = ""
    format: str = SITE_FORMAT
    # the rules the lidar landmarks of features.csv were extracted by (None: no landmarks), so
    # that a scan is read by the same rules (initcli.core.lidar.scan_landmarks.ScanLandmarkParams.from_rules)
    landmarks: LandmarkSettings | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": self.format,
            "tool": {"name": "bim-extract", "version": self.tool_version},
            "source": {"file": self.source_file, "sha256": self.source_sha256},
            "schema": self.schema,
            "application": self.application,
            "length_unit": self.length_unit,
            "unit_scale": self.unit_scale,
            "section_height": self.section_height,
            "resolution": self.resolution,
            "storeys": [asdict(s) for s in self.storeys],
            "files": list(self.files),
            **({"landmarks": landmark_rules(self.landmarks)} if self.landmarks is not None else {}),
        }

    @classmethod
    def from_dict(cls, doc: dict[str, Any], where: str = "site.json") -> SiteManifest:
        fmt = doc.get("format", SITE_FORMAT) if isinstance(doc, dict) else SITE_FORMAT
        if fmt != SITE_FORMAT:
            raise InputError(
                f"{where}: format {fmt!r} is not one this bim-init reads ({SITE_FORMAT}); extract the site"
                " again with this version, or update bim-init"
            )
        try:
            return cls(
                source_file=doc["source"]["file"],
                source_sha256=doc["source"]["sha256"],
                schema=doc["schema"],
                application=doc.get("application", ""),
                length_unit=doc.get("length_unit", ""),
                unit_scale=float(doc.get("unit_scale", 1.0)),
                section_height=float(doc["section_height"]),
                resolution=float(doc.get("resolution", 0.05)),
                storeys=[_storey(s, f"{where}: storeys.{i}") for i, s in enumerate(doc["storeys"])],
                files=list(doc.get("files", [])),
                tool_version=doc.get("tool", {}).get("version", ""),
                format=doc.get("format", SITE_FORMAT),
                landmarks=parse_landmarks(doc["landmarks"], f"{where}: landmarks")
                if "landmarks" in doc
                else None,
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"{where}: malformed manifest ({exc!s})") from None


def _storey(entry: object, where: str) -> StoreyInfo:
    """One storey of the manifest; its map and preview are plain file names in the site folder."""
    if not isinstance(entry, dict):
        raise InputError(f"{where}: expected an object")
    info = StoreyInfo(**entry)
    if not isinstance(info.name, str):
        raise InputError(f"{where}.name: expected text, got {info.name!r}")
    for key in ("map_yaml", "preview"):
        value = getattr(info, key)
        if value is not None and (
            not isinstance(value, str) or Path(value).name != value or value in ("", ".", "..")
        ):
            raise InputError(f"{where}.{key}: expected a file name in the site folder, got {value!r}")
    return info


def landmark_rules(settings: LandmarkSettings) -> dict[str, Any]:
    """The landmarks: block as site.json records it (the categories file's keys, lists for pairs)."""
    doc = asdict(settings)
    return {k: list(v) if isinstance(v, tuple) else v for k, v in doc.items()}


def format_manifest(manifest: SiteManifest) -> str:
    return json.dumps(manifest.to_dict(), indent=2) + "\n"


def read_manifest(path: Path) -> SiteManifest:
    path = Path(path)
    return SiteManifest.from_dict(read_json(path), str(path))
