"""The defaults and ranges of bim-extract's settings (light: the CLI reads them without ifcopenshell)."""

from __future__ import annotations

__all__ = ["DEFAULT_RESOLUTION", "DEFAULT_SECTION_HEIGHT", "RESOLUTION_RANGE", "SECTION_HEIGHT_RANGE"]

DEFAULT_SECTION_HEIGHT = 1.0  # m above each storey's elevation
DEFAULT_RESOLUTION = 0.05  # m per map pixel
SECTION_HEIGHT_RANGE = {"above": 0.0, "maximum": 10.0}  # m: (0, 10]
RESOLUTION_RANGE = {"minimum": 0.005, "maximum": 1.0}  # m per pixel: [0.005, 1]
