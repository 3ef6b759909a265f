"""The elements an extraction looks at: the candidates of each feature category, door bodies and
the storeys elements stand on (:func:`collect_candidates`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import ifcopenshell
import ifcopenshell.util.element
import ifcopenshell.util.placement
import numpy as np

from bimtools.ifc.categories import CategorySet
from bimtools.ifc.geometry import Mesh
from bimtools.ifc.storeys import Storey, container_storey, storey_at_elevation

__all__ = [
    "CURTAIN_PART_CLASSES",
    "OBSTACLE_CLASSES",
    "STAIR_PART_EXCLUDED",
    "Candidates",
    "ElementStoreys",
    "collect_candidates",
    "door_without_body",
    "placement_axes",
]

OBSTACLE_CLASSES = ("IfcWall", "IfcColumn", "IfcCurtainWall", "IfcDoor", "IfcWindow")
CURTAIN_PART_CLASSES = ("IfcPlate", "IfcMember")
STAIR_PART_EXCLUDED = "IfcRailing"  # a stair's railing stands beside its flights, not on its walking line


def _is_curtain_part(element: ifcopenshell.entity_instance) -> bool:
    parent = ifcopenshell.util.element.get_aggregate(element)
    return parent is not None and parent.is_a("IfcCurtainWall")


def placement_axes(element: ifcopenshell.entity_instance) -> tuple[np.ndarray, np.ndarray]:
    matrix = ifcopenshell.util.placement.get_local_placement(element.ObjectPlacement)
    return np.asarray(matrix[:3, 0]), np.asarray(matrix[:3, 1])


@dataclass
class Candidates:
    """The elements whose geometry the extraction needs, by role."""

    obstacles: list[ifcopenshell.entity_instance]
    doors: list[ifcopenshell.entity_instance]
    bodies: list[ifcopenshell.entity_instance]
    body_category: dict[int, str]  # entity id -> category name
    spaces: list[ifcopenshell.entity_instance]
    # door GlobalId -> the opening it fills, for doors without a body (placed from the opening)
    openings: dict[str, ifcopenshell.entity_instance] = field(default_factory=dict)
    slabs: list[ifcopenshell.entity_instance] = field(default_factory=list)  # floors: the footprint
    # the parts a stair aggregates (flights, landings as IfcSlab, stringers): their bodies are its body
    parts: list[ifcopenshell.entity_instance] = field(default_factory=list)

    def all(self) -> list[ifcopenshell.entity_instance]:
        unique: dict[int, ifcopenshell.entity_instance] = {}
        parts = [
            *self.obstacles,
            *self.doors,
            *self.spaces,
            *self.bodies,
            *self.openings.values(),
            *self.slabs,
            *self.parts,
        ]
        for element in parts:
            unique.setdefault(element.id(), element)
        return list(unique.values())


def collect_candidates(model: ifcopenshell.file, categories: CategorySet) -> Candidates:
    obstacles = [e for cls in OBSTACLE_CLASSES for e in model.by_type(cls)]
    obstacles += [e for cls in CURTAIN_PART_CLASSES for e in model.by_type(cls) if _is_curtain_part(e)]
    door_classes = {c for cat in categories.categories for rule in cat.doors for c in rule.classes}
    doors: list[ifcopenshell.entity_instance] = []
    for cls in sorted(door_classes):
        for element in model.by_type(cls):
            if any(cat.is_door(element) for cat in categories.categories):
                doors.append(element)
    body_classes = {c for cat in categories.categories for rule in cat.bodies for c in rule.classes}
    body_category: dict[int, str] = {}
    bodies: list[ifcopenshell.entity_instance] = []
    for cls in sorted(body_classes):
        for element in model.by_type(cls):
            for cat in categories.categories:
                if (
                    cat.kind in ("lift", "stairs")
                    and cat.is_body(element)
                    and element.id() not in body_category
                ):
                    body_category[element.id()] = cat.name
                    bodies.append(element)
    parts = [
        child
        for body in bodies
        for child in ifcopenshell.util.element.get_decomposition(body)
        if child.is_a("IfcElement") and not child.is_a(STAIR_PART_EXCLUDED)
    ]
    unique_doors = list({d.id(): d for d in doors}.values())
    openings: dict[str, ifcopenshell.entity_instance] = {}
    for door in unique_doors:
        if getattr(door, "Representation", None) is None:
            for rel in getattr(door, "FillsVoids", None) or ():
                openings[door.GlobalId] = rel.RelatingOpeningElement
    return Candidates(
        obstacles,
        unique_doors,
        bodies,
        body_category,
        list(model.by_type("IfcSpace")),
        openings,
        list(model.by_type("IfcSlab")),
        parts,
    )


def _placement_box(element: ifcopenshell.entity_instance, width: float, height: float) -> np.ndarray:
    """Corner points of a door's opening from its placement alone: the IFC convention puts the
    origin at the lining's corner at floor level, with the door running +X for its width."""
    matrix = np.asarray(ifcopenshell.util.placement.get_local_placement(element.ObjectPlacement))
    origin, x_axis, z_axis = matrix[:3, 3], matrix[:3, 0], matrix[:3, 2]
    return np.array([origin + x_axis * u + z_axis * v for u in (0.0, width) for v in (0.0, height)])


def door_without_body(
    element: ifcopenshell.entity_instance,
    candidates: Candidates,
    meshes: dict[str, Mesh],
    scale: float,
) -> np.ndarray | None:
    """Plan points of a door that has no body: the opening it fills, else its placement and
    OverallWidth/OverallHeight; None when neither is known."""
    opening = candidates.openings.get(element.GlobalId)
    if opening is not None and opening.GlobalId in meshes:
        return meshes[opening.GlobalId].verts
    width = getattr(element, "OverallWidth", None)
    height = getattr(element, "OverallHeight", None)
    if not width or getattr(element, "ObjectPlacement", None) is None:
        return None
    # Placement is in project units; meshes are in metres.
    box = _placement_box(element, float(width), float(height or 2.1 / scale))
    return box * scale


class ElementStoreys:
    """Which storey each element stands on: its spatial container, else its lowest point."""

    def __init__(self, storeys: list[Storey], meshes: dict[str, Mesh]):
        self.storeys = storeys
        self.by_entity = {s.entity.id(): s for s in storeys}
        self.meshes = meshes
        self._cache: dict[int, Storey | None] = {}

    def of(self, element: ifcopenshell.entity_instance) -> Storey | None:
        """The container storey; but geometry standing on a higher storey's floor wins (exports put
        e.g. upper landing doors in the lowest level), and uncontained elements go by elevation."""
        cached = self._cache.get(element.id())
        if cached is not None or element.id() in self._cache:
            return cached
        container = container_storey(element)
        mesh = self.meshes.get(element.GlobalId)
        by_height = storey_at_elevation(self.storeys, mesh.zmin) if mesh is not None else None
        storey: Storey | None
        if container is not None and container.id() in self.by_entity:
            storey = self.by_entity[container.id()]
            if by_height is not None and by_height.elevation > storey.elevation + 0.5:
                storey = by_height
        else:
            storey = by_height
        self._cache[element.id()] = storey
        return storey
