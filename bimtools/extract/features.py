"""Feature extraction for one storey: doors, lift entrances, staircase entrances (paper Table 1).

Inputs are element candidates already placed in plan (see :mod:`bimtools.extract.placement`) and
the storey's free-space regions and spaces (see :mod:`bimtools.extract.circulation`).

Order of claims follows the categories file: a door that is a lift landing door or the door into
a stair enclosure becomes a Lift / Stairs feature and not also a Door.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from bimtools.extract.circulation import FreeRegions, SideProbe, SpaceIndex, choose_side, probe_side
from bimtools.extract.placement import Front, Opening, rectangle_fronts, stair_foot
from bimtools.ifc.categories import Category, CategorySet
from bimtools.site.records import Feature

if TYPE_CHECKING:
    import ifcopenshell

__all__ = [
    "BodyCandidate",
    "DoorCandidate",
    "ENCLOSURE_DOOR_RADIUS",
    "ENTRANCE_RADIUS",
    "FOOT_CLEARANCE",
    "FOOT_STEPS",
    "StoreyContext",
    "decide_sides",
    "is_shaft_space",
    "storey_features",
]

ENTRANCE_RADIUS = 2.5  # metres: a door this close to a lift/stair body is its entrance
ENCLOSURE_DOOR_RADIUS = 5.0  # metres: a door into a body's enclosure this close to the body enters it
FOOT_CLEARANCE = 0.35  # metres in front of a stair's foot that must be free floor ...
FOOT_STEPS = np.arange(0.1, FOOT_CLEARANCE + 1e-9, 0.05)  # ... sampled every 5 cm from 0.1 m


@dataclass
class DoorCandidate:
    """A door-like element on this storey with its plan geometry."""

    guid: str
    ifc_class: str
    name: str
    opening: Opening
    entity: ifcopenshell.entity_instance  # for category rules
    plus: SideProbe | None = None
    minus: SideProbe | None = None
    side: int = 1
    rule: str = ""

    def probes(self) -> tuple[SideProbe, SideProbe]:
        """The (plus, minus) sides, once :func:`decide_sides` has probed them."""
        assert self.plus is not None and self.minus is not None, "decide_sides probes the sides first"
        return self.plus, self.minus

    @property
    def circulation(self) -> SideProbe:
        return self.plus if self.side > 0 else self.minus  # type: ignore[return-value]

    @property
    def room(self) -> SideProbe:
        return self.minus if self.side > 0 else self.plus  # type: ignore[return-value]


@dataclass
class BodyCandidate:
    """A lift car/shaft or staircase present on this storey."""

    guid: str
    ifc_class: str
    name: str
    category: str
    footprint: BaseGeometry  # plan area on this storey
    points: np.ndarray  # plan points sampled from it (for region look-up)
    parts: list[np.ndarray] = field(default_factory=list)  # 3D vertex arrays (stairs: flights)
    starts_here: bool = True  # stairs: its foot is on this storey
    height: float = 2.1


@dataclass
class StoreyContext:
    name: str
    elevation: float
    regions: FreeRegions
    spaces: SpaceIndex
    categories: CategorySet
    warnings: list[str] = field(default_factory=list)  # what a user should hear (bim-extract prints them)
    skipped: list[tuple[str, str]] = field(default_factory=list)  # (IFC class, why): the summary counts them


def _enclosure_space(categories: CategorySet, name: str) -> bool:
    return any(c.kind in ("lift", "stairs") and c.is_space(name) for c in categories.categories)


def _mark_vertical(ctx: StoreyContext, side: SideProbe) -> None:
    if side.label:
        ctx.regions.vertical[side.label] = True
    if side.space_index >= 0:
        ctx.spaces.vertical[side.space_index] = True


def _probe(ctx: StoreyContext, point: np.ndarray, direction: np.ndarray) -> SideProbe:
    """What lies from plan ``point`` towards ``direction`` on this storey."""
    return probe_side(ctx.regions, ctx.spaces, point[0], point[1], direction)


def decide_sides(
    ctx: StoreyContext, doors: list[DoorCandidate], bodies: list[BodyCandidate] | None = None
) -> None:
    """Probe both sides of every door, count doors per free region and space, find the places
    that lead to a staircase or lift, then pick circulation sides."""
    for door in doors:
        o = door.opening
        plus = door.plus = _probe(ctx, o.face(+1), o.across)
        minus = door.minus = _probe(ctx, o.face(-1), -o.across)
        for label in {plus.label, minus.label} - {0}:
            ctx.regions.doors[label] += 1
        for index in {plus.space_index, minus.space_index} - {-1}:
            ctx.spaces.doors[index] += 1
    # A place holding a stair or lift, or linked to one by a door, leads to another storey.
    body_labels: set[int] = set()
    for body in bodies or []:
        body_labels |= ctx.regions.labels_at(body.points)
    for label in body_labels:
        ctx.regions.vertical[label] = True
    probed = [(door, *door.probes()) for door in doors]
    for _, plus, minus in probed:
        for this, other in ((plus, minus), (minus, plus)):
            if this.label in body_labels or _enclosure_space(ctx.categories, this.space):
                _mark_vertical(ctx, other)
    for door, plus, minus in probed:
        door.side, door.rule = choose_side(
            plus,
            minus,
            ctx.regions,
            ctx.categories.is_circulation,
            lambda name: _enclosure_space(ctx.categories, name),
            ctx.spaces,
        )


def _feature(
    ctx: StoreyContext, guid: str, category: str, front: Front, ifc_class: str, name: str
) -> Feature:
    n = front.normal / max(float(np.hypot(*front.normal)), 1e-12)
    return Feature(
        id=guid,
        category=category,
        x=float(front.point[0]),
        y=float(front.point[1]),
        norm_x=float(n[0]),
        norm_y=float(n[1]),
        width=float(front.width),
        height=float(front.height),
        storey=ctx.name,
        elevation=ctx.elevation,
        ifc_class=ifc_class,
        name=name,
    )


def _door_front(door: DoorCandidate) -> Front:
    o = door.opening
    return Front(point=o.face(door.side), normal=door.side * o.across, width=o.width, height=o.height)


def _body_regions(ctx: StoreyContext, body: BodyCandidate, category: Category) -> set[int]:
    """Free regions that count as this body's enclosure (small, holding the body)."""
    labels = ctx.regions.labels_at(body.points)
    return {lab for lab in labels if ctx.regions.areas[lab] <= category.enclosure_max_area}


def is_shaft_space(category: Category, area: float) -> bool:
    """A lift space is a shaft only when small: a big space named "Elevator (N.I.C.)" or "Aufzug
    lobby" is a lobby or a placeholder, and its doors are not lift doors."""
    return category.kind != "lift" or area <= category.enclosure_max_area


def _door_distance(body: BodyCandidate, door: DoorCandidate) -> float:
    """Metres from a body's footprint to the centre of a door's opening."""
    return float(body.footprint.distance(shapely.Point(*door.opening.centre)))


def _enters_enclosure(door: DoorCandidate, body: BodyCandidate, enclosure: set[int]) -> bool:
    """Does ``door`` open into ``enclosure`` (the small regions holding ``body``) near the body? A
    1.8 m wide hall of 50 m^2 holding a stair at one end is no stairwell to a glass door 7 m away
    at the other."""
    return door.room.label in enclosure and _door_distance(body, door) <= ENCLOSURE_DOOR_RADIUS


def _is_entrance(
    ctx: StoreyContext,
    door: DoorCandidate,
    category: Category,
    enclosures: list[tuple[BodyCandidate, set[int]]],
) -> bool:
    if category.is_door(door.entity):
        return True
    if not door.room.reachable:
        return False  # an exterior door leads out of the building, not into a shaft or stairwell
    if (
        category.is_space(door.room.space)
        and not ctx.categories.is_circulation(door.room.space)
        and is_shaft_space(category, door.room.space_area)
    ):
        return True
    if door.room.label == 0 or door.room.label == door.circulation.label:
        return False
    return any(_enters_enclosure(door, body, enclosure) for body, enclosure in enclosures)


def _best_front(ctx: StoreyContext, footprint: BaseGeometry, exclude: set[int]) -> Front | None:
    """The side of a shaft footprint that faces the circulation area."""
    best: tuple[tuple, Front] | None = None
    for front in rectangle_fronts(footprint):
        probe = _probe(ctx, front.point, front.normal)
        circulation = ctx.categories.is_circulation(probe.space)
        label_score = ctx.regions.score(probe.label) if probe.label not in exclude else (-1, 0.0)
        key = (probe.reachable, circulation, label_score, front.width)
        if best is None or key > best[0]:
            best = (key, front)
    return best[1] if best else None


def storey_features(
    ctx: StoreyContext, doors: list[DoorCandidate], bodies: list[BodyCandidate]
) -> list[Feature]:
    decide_sides(ctx, doors, bodies)
    features: list[Feature] = []
    claimed: set[str] = set()
    for category in ctx.categories.categories:
        if category.kind == "door":
            for door in doors:
                if door.guid not in claimed and category.is_door(door.entity):
                    claimed.add(door.guid)
                    features.append(
                        _feature(ctx, door.guid, category.name, _door_front(door), door.ifc_class, door.name)
                    )
            continue
        own_bodies = [b for b in bodies if b.category == category.name]
        enclosures = [(b, _body_regions(ctx, b, category)) for b in own_bodies]
        entrances: list[DoorCandidate] = []
        for door in doors:
            if door.guid not in claimed and _is_entrance(ctx, door, category, enclosures):
                claimed.add(door.guid)
                entrances.append(door)
                features.append(
                    _feature(ctx, door.guid, category.name, _door_front(door), door.ifc_class, door.name)
                )
        served: list[BaseGeometry] = []
        for body, enclosure in enclosures:
            near = any(
                _enters_enclosure(door, body, enclosure) or _door_distance(body, door) <= ENTRANCE_RADIUS
                for door in entrances
            )
            if near or any(body.footprint.distance(s) < 1.0 for s in served):
                continue
            front = _body_front(ctx, body, category)
            if front is None:
                continue
            served.append(body.footprint)
            features.append(_feature(ctx, body.guid, category.name, front, body.ifc_class, body.name))
    return features


def _body_front(ctx: StoreyContext, body: BodyCandidate, category: Category) -> Front | None:
    if category.kind == "stairs":
        if not body.starts_here:
            return None
        foot = stair_foot(body.parts)
        if foot is None:
            ctx.warnings.append(
                f"storey {ctx.name!r}: stair {body.name!r} ({body.guid}): no foot found, skipped"
            )
            ctx.skipped.append((body.ifc_class, "no foot found"))
            return None
        # A stair whose foot is seen only from outside the building (an exterior stair) is not a
        # feature a robot inside can reach; nor one whose foot faces a wall (the floor right in
        # front of it is not free): its climb was misread, and a front through a wall would have
        # the robot expect to see it from the room behind.
        ahead = _probe(ctx, foot.point, foot.normal)
        floor = [foot.point + t * foot.normal for t in FOOT_STEPS]
        if ahead.reachable and all(ctx.regions.label_at(*p) for p in floor):
            return foot
        why = "its foot faces a wall" if ahead.reachable else "its foot is outside the building"
        ctx.warnings.append(f"storey {ctx.name!r}: stair {body.name!r} ({body.guid}): {why}, skipped")
        ctx.skipped.append((body.ifc_class, why))
        return None
    front = _best_front(ctx, body.footprint, set())
    if front is None:
        return None
    return Front(point=front.point, normal=front.normal, width=min(front.width, 2.0), height=body.height)
