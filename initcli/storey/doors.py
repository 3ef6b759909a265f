"""Closed door leaves: the design's doors as the simulated world and the survey have them (the map
leaves door openings free)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Protocol

import numpy as np

from bimtools.site.records import Feature, Obstacle
from initcli.storey.outlines import box_ring

__all__ = ["DoorFeature", "LEAF_CLASS", "LEAF_THICKNESS", "closed_doors", "door_ids", "door_leaf"]

LEAF_THICKNESS = 0.04  # m: a closed door leaf
LEAF_CLASS = "DoorLeaf"


class DoorFeature(Protocol):
    """A door as a feature: its id, the centre of its face, the face's unit normal and its width (a
    BIM ``Feature`` or the simulator's ``SimFeature``)."""

    @property
    def id(self) -> str: ...
    @property
    def x(self) -> float: ...
    @property
    def y(self) -> float: ...
    @property
    def norm_x(self) -> float: ...
    @property
    def norm_y(self) -> float: ...
    @property
    def width(self) -> float: ...


def door_leaf(f: DoorFeature) -> Obstacle:
    """A closed leaf across the opening of door feature ``f``, just behind its face."""
    along = np.array([-f.norm_y, f.norm_x])
    centre = np.array([f.x, f.y]) - (LEAF_THICKNESS / 2 + 0.01) * np.array([f.norm_x, f.norm_y])
    ring = box_ring(centre, along, max(f.width, 0.6) / 2, LEAF_THICKNESS / 2)
    return Obstacle("", f.id, LEAF_CLASS, tuple(map(tuple, ring[:-1].tolist())))


def door_ids(features: Iterable[Feature]) -> frozenset[str]:
    """Ids of the BIM features that are doors with a leaf (IfcDoor; not lifts, stairs or openings)."""
    return frozenset(f.id for f in features if f.ifc_class == "IfcDoor")


def closed_doors(features: Iterable[DoorFeature], doors: frozenset[str]) -> list[Obstacle]:
    """A closed :func:`door_leaf` for each of ``features`` whose id is in ``doors``: the design's doors
    as the simulated world has them (the map leaves door openings free)."""
    return [door_leaf(f) for f in features if f.id in doors]
