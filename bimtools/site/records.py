"""Typed records of the site model (paper Table 1 features, wall surfaces, obstacles)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

# The first eight columns of features.csv are exactly the paper's Table 1.
TABLE1_COLUMNS = ("ID", "Category", "X", "Y", "Norm_X", "Norm_Y", "Width", "Height")
EXTRA_COLUMNS = ("Storey", "Elevation", "IfcClass", "Name")
FEATURE_COLUMNS = TABLE1_COLUMNS + EXTRA_COLUMNS

BUILTIN_CATEGORIES = ("Door", "Lift", "Stairs")


@dataclass(frozen=True)
class Feature:
    """One BIM feature b_u (Eq. 4): a door, lift or staircase entrance seen from circulation.

    ``x, y`` is the centre of the element's face at floor level in the world XY frame (metres);
    ``norm_x, norm_y`` the unit normal pointing to the side a robot sees it from.
    """

    id: str
    category: str
    x: float
    y: float
    norm_x: float
    norm_y: float
    width: float
    height: float
    storey: str = ""
    elevation: float = 0.0
    ifc_class: str = ""
    name: str = ""

    @property
    def heading(self) -> float:
        """Direction of the normal in radians."""
        return math.atan2(self.norm_y, self.norm_x)


@dataclass(frozen=True)
class WallSegment:
    """A straight piece of wall surface cut at the section height (used by Eq. 17).

    ``normal`` is the unit vector pointing from the wall into free space.
    """

    storey: str
    element: str
    ifc_class: str
    x1: float
    y1: float
    x2: float
    y2: float
    normal: tuple[float, float]

    @property
    def length(self) -> float:
        return math.hypot(self.x2 - self.x1, self.y2 - self.y1)


@dataclass(frozen=True)
class Obstacle:
    """The footprint of a solid element at the section height (wall, column, closed door...)."""

    storey: str
    element: str
    ifc_class: str
    exterior: tuple[tuple[float, float], ...]
    holes: tuple[tuple[tuple[float, float], ...], ...] = ()


@dataclass
class StoreyInfo:
    """What the manifest says of one storey."""

    name: str
    elevation: float
    counts: dict[str, int] = field(default_factory=dict)
    map_yaml: str | None = None
    preview: str | None = None
