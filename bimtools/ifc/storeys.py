"""Building storeys: names, elevations in metres, and which storey an element stands on."""

from __future__ import annotations

from dataclasses import dataclass

import ifcopenshell
import ifcopenshell.util.element
import ifcopenshell.util.placement

from bimtools.site.names import storey_slug, storey_slugs

__all__ = ["Storey", "container_storey", "list_storeys", "storey_at_elevation", "storey_slug"]


@dataclass
class Storey:
    name: str
    elevation: float  # metres, world z of the storey's floor level
    entity: ifcopenshell.entity_instance
    slug: str = ""


def _placement_z(entity: ifcopenshell.entity_instance, scale: float) -> float | None:
    if getattr(entity, "ObjectPlacement", None) is None:
        return None
    try:
        return float(ifcopenshell.util.placement.get_local_placement(entity.ObjectPlacement)[2, 3]) * scale
    except Exception:
        return None


def list_storeys(model: ifcopenshell.file, scale: float) -> list[Storey]:
    """All storeys sorted by elevation, with unique names and slugs.

    Elevation comes from ``Elevation`` when given, else from the storey's placement (storeys
    without an elevation are common in files from some tools).
    """
    entities = model.by_type("IfcBuildingStorey")
    storeys: list[Storey] = []
    for index, entity in enumerate(entities):
        elevation: float | None = None
        if getattr(entity, "Elevation", None) is not None:
            elevation = float(entity.Elevation) * scale
            # Elevation is relative to the building in IFC; world placement z is authoritative when
            # the two disagree (rare). Use placement when it is set and Elevation is zero.
            placed = _placement_z(entity, scale)
            if placed is not None and abs(elevation) < 1e-9 and abs(placed) > 1e-6:
                elevation = placed
        else:
            elevation = _placement_z(entity, scale)
        name = (
            (entity.Name or entity.LongName or f"Storey {index + 1}").strip()
            if hasattr(entity, "LongName")
            else (entity.Name or f"Storey {index + 1}")
        )
        storeys.append(
            Storey(name=name, elevation=elevation if elevation is not None else float("nan"), entity=entity)
        )
    # Storeys with neither Elevation nor placement keep file order, spaced 3 m apart.
    for index, storey in enumerate(storeys):
        if storey.elevation != storey.elevation:  # NaN
            storey.elevation = 3.0 * index
        elif abs(storey.elevation) < 1e-6:  # a rounding residue (-2e-11 mm): 0.00, never -0.00
            storey.elevation = 0.0
    storeys.sort(key=lambda s: s.elevation)
    seen: dict[str, int] = {}
    for storey in storeys:
        base = storey.name
        if base in seen:
            seen[base] += 1
            storey.name = f"{base} ({seen[base]})"
        else:
            seen[base] = 1
    for storey, slug in zip(storeys, storey_slugs(s.name for s in storeys), strict=True):
        storey.slug = slug  # bimtools.site.names: the one rule for storey names in file names
    return storeys


def container_storey(element: ifcopenshell.entity_instance) -> ifcopenshell.entity_instance | None:
    """The storey that contains ``element`` (through spaces and aggregates), if any."""
    node = ifcopenshell.util.element.get_container(element)
    if node is None:
        parent = ifcopenshell.util.element.get_aggregate(element)
        if parent is not None and parent.is_a("IfcBuildingStorey"):
            return parent
        if parent is not None:
            node = ifcopenshell.util.element.get_container(parent)
    for _ in range(8):
        if node is None:
            return None
        if node.is_a("IfcBuildingStorey"):
            return node
        node = ifcopenshell.util.element.get_aggregate(node) or ifcopenshell.util.element.get_container(node)
    return None


def storey_at_elevation(storeys: list[Storey], z: float, tolerance: float = 0.3) -> Storey:
    """The highest storey whose floor is at or below ``z`` (+ tolerance); the lowest one otherwise."""
    candidates = [s for s in storeys if s.elevation <= z + tolerance]
    return candidates[-1] if candidates else storeys[0]
