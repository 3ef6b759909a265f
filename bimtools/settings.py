"""The defaults and ranges of bim-extract's settings (light: the CLI reads them without ifcopenshell)."""

from __future__ import annotations

from dataclasses import dataclass

from bimkit.checks import range_problem
from bimkit.errors import InputError

__all__ = [
    "DEFAULT_RESOLUTION",
    "DEFAULT_SECTION_HEIGHT",
    "MAX_STOREY_ELEVATION",
    "RESOLUTION_RANGE",
    "SECTION_HEIGHT_RANGE",
]

DEFAULT_SECTION_HEIGHT = 1.0  # m above each storey's elevation
DEFAULT_RESOLUTION = 0.05  # m per map pixel
SECTION_HEIGHT_RANGE = {"above": 0.0, "maximum": 10.0}  # m: (0, 10]
RESOLUTION_RANGE = {"minimum": 0.005, "maximum": 1.0}  # m per pixel: [0.005, 1]
MAX_STOREY_ELEVATION = 10_000.0  # m: a storey floor beyond +-10 km is a unit or export error


@dataclass(frozen=True)
class LandmarkSettings:
    """What makes a wall corner, a column corner or an opening a lidar landmark: the categories
    file's ``landmarks:`` block (documented in ``bimtools/default_categories.yaml``). A file
    without the block has them off: features.csv holds the camera features only."""

    enabled: bool = False
    corner_angle: tuple[float, float] = (60.0, 120.0)  # degrees between the two wall faces
    min_leg: float = 0.3  # m: both faces of a corner at least this long (no mouldings, no jogs)
    column_max_side: float = 1.0  # m: a free-standing solid no longer than this each way is a column
    opening_width: tuple[float, float] = (0.7, 2.5)  # m: gap in a wall line (door widths)
    min_recess: float = 0.05  # m: how far behind the wall line a gap's floor must lie (a door leaf)


# Ranges of the block's numbers (bimkit/schemas/categories.schema.json says the same).
LANDMARK_RANGES: dict[str, dict[str, float]] = {
    "corner_angle": {"above": 0.0, "below": 180.0},  # degrees, each end
    "min_leg": {"above": 0.0, "maximum": 10.0},  # m
    "column_max_side": {"above": 0.0, "maximum": 10.0},  # m
    "opening_width": {"above": 0.0, "maximum": 20.0},  # m, each end
    "min_recess": {"above": 0.0, "maximum": 1.0},  # m
}


def _pair(value: object, where: str, bounds: dict[str, float]) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise InputError(f"{where}: expected [low, high], got {value!r}")
    for i, v in enumerate(value):
        problem = range_problem(v, **bounds)
        if problem is not None:
            raise InputError(f"{where}[{i}]: {problem}")
    lo, hi = float(value[0]), float(value[1])
    if lo > hi:
        raise InputError(f"{where}: low {value[0]} is above high {value[1]}")
    return lo, hi


def parse_landmarks(doc: object, where: str) -> LandmarkSettings:
    """The ``landmarks:`` block of a categories file (None: absent, landmarks off)."""
    if doc is None:
        return LandmarkSettings()
    if not isinstance(doc, dict):
        raise InputError(f"{where}: expected a mapping (enabled, corner_angle, min_leg, ...)")
    known = {"enabled", *LANDMARK_RANGES}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise InputError(
            f"{where}: unknown key(s) {', '.join(map(str, unknown))} (known: {', '.join(sorted(known))})"
        )
    enabled = doc.get("enabled", True)
    if not isinstance(enabled, bool):
        raise InputError(f"{where}.enabled: expected true or false, got {enabled!r}")
    values: dict[str, object] = {"enabled": enabled}
    for key in ("corner_angle", "opening_width"):
        if key in doc:
            values[key] = _pair(doc[key], f"{where}.{key}", LANDMARK_RANGES[key])
    for key in ("min_leg", "column_max_side", "min_recess"):
        if key in doc:
            problem = range_problem(doc[key], **LANDMARK_RANGES[key])
            if problem is not None:
                raise InputError(f"{where}.{key}: {problem}")
            values[key] = float(doc[key])
    return LandmarkSettings(**values)  # type: ignore[arg-type]
