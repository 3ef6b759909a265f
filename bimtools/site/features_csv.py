"""``features.csv``: the paper's Table 1 plus storey, elevation, IFC class and name.

Only the eight Table 1 columns are required when reading, so a hand-written Table 1 works.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable
from pathlib import Path

from bimkit.checks import read_text
from bimkit.errors import InputError
from bimtools.site.records import EXTRA_COLUMNS, FEATURE_COLUMNS, TABLE1_COLUMNS, Feature

MAX_FEATURE_SIZE = 50.0  # m: the widest or tallest door, lift or stairs a building has, and more


def format_features(features: Iterable[Feature]) -> str:
    """Render features as CSV text (metres, 4 decimals; normals 6 decimals)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(FEATURE_COLUMNS)
    for f in features:
        writer.writerow(
            [
                f.id,
                f.category,
                f"{f.x:.4f}",
                f"{f.y:.4f}",
                f"{round(f.norm_x, 6) + 0.0:.6f}",
                f"{round(f.norm_y, 6) + 0.0:.6f}",
                f"{f.width:.3f}",
                f"{f.height:.3f}",
                f.storey,
                f"{f.elevation:.4f}",
                f.ifc_class,
                f.name,
            ]
        )
    return out.getvalue()


def write_features(path: Path, features: Iterable[Feature]) -> None:
    Path(path).write_text(format_features(features), encoding="utf-8")


MAX_COORDINATE = 1e6  # m: positions, sizes and elevations of a building's features


def _number(path: Path, line: int, column: str, text: str) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise InputError(f"{path}:{line}: column {column}: expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise InputError(f"{path}:{line}: column {column}: expected a finite number, got {text!r}")
    if abs(value) > MAX_COORDINATE:
        raise InputError(f"{path}:{line}: column {column}: {text} is outside +-{MAX_COORDINATE:g} m")
    return value


def read_features(path: Path) -> list[Feature]:
    """Read a features.csv; raise :class:`InputError` naming ``file:line`` on a bad row."""
    return [f for _, f in read_feature_rows(path)]


def read_feature_rows(path: Path) -> list[tuple[int, Feature]]:
    """The features of a features.csv with the line each ends on (for messages of later checks)."""
    path = Path(path)
    text = read_text(path, "a feature table (features.csv)", encoding="utf-8-sig")
    reader = csv.DictReader(io.StringIO(text, newline=""))
    try:
        return _rows(path, reader)
    except csv.Error as exc:
        raise InputError(f"{path}:{reader.line_num}: not a CSV row ({exc})") from None


def _rows(path: Path, reader: csv.DictReader[str]) -> list[tuple[int, Feature]]:
    header = [h.strip() for h in (reader.fieldnames or [])]
    missing = [c for c in TABLE1_COLUMNS if c not in header]
    if missing:
        raise InputError(
            f"{path}:1: missing column(s) {', '.join(missing)} (Table 1 needs {','.join(TABLE1_COLUMNS)})"
        )
    reader.fieldnames = header
    features: list[tuple[int, Feature]] = []
    first_line: dict[tuple[str, str], int] = {}  # (ID, Storey) -> the line it was first on
    for row in reader:
        line = reader.line_num
        if not any((v or "").strip() for v in row.values() if isinstance(v, str)):
            continue
        values = {k: (row.get(k) or "").strip() for k in FEATURE_COLUMNS}
        if not values["ID"]:
            raise InputError(f"{path}:{line}: column ID is empty")
        if not values["Category"]:
            raise InputError(f"{path}:{line}: column Category is empty")
        nx = _number(path, line, "Norm_X", values["Norm_X"])
        ny = _number(path, line, "Norm_Y", values["Norm_Y"])
        norm = math.hypot(nx, ny)
        if norm < 1e-9:
            raise InputError(f"{path}:{line}: Norm_X, Norm_Y is the zero vector")
        feature = Feature(
            id=values["ID"],
            category=values["Category"],
            x=_number(path, line, "X", values["X"]),
            y=_number(path, line, "Y", values["Y"]),
            norm_x=nx / norm,
            norm_y=ny / norm,
            width=_number(path, line, "Width", values["Width"]),
            height=_number(path, line, "Height", values["Height"]),
            storey=values["Storey"],
            elevation=_number(path, line, "Elevation", values["Elevation"]) if values["Elevation"] else 0.0,
            ifc_class=values["IfcClass"],
            name=values["Name"],
        )
        for key, size in (("Width", feature.width), ("Height", feature.height)):
            if not 0.0 <= size <= MAX_FEATURE_SIZE:
                raise InputError(
                    f"{path}:{line}: column {key} is {size:g} m; no door, lift or stairs is outside"
                    f" 0 to {MAX_FEATURE_SIZE:g} m"
                )
        seen = first_line.setdefault((feature.id, feature.storey), line)
        if seen != line:
            raise InputError(
                f"{path}:{line}: ID {feature.id} on storey {feature.storey!r} is on line {seen} already"
                " (one row per element and storey)"
            )
        features.append((line, feature))
    return features


__all__ = [
    "EXTRA_COLUMNS",
    "MAX_FEATURE_SIZE",
    "format_features",
    "read_feature_rows",
    "read_features",
    "write_features",
]
