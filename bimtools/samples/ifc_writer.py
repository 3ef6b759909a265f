"""Build an IFC4 model of a :class:`~bimtools.samples.layouts.FloorPlan` with ``ifcopenshell.api``.

Spatial tree: IfcProject > IfcSite > IfcBuilding > IfcBuildingStorey "Level 1" (elevation 0.0,
GrossHeight 3.0 in Qto_BuildingStoreyBaseQuantities). Walls, doors, lift cars and stairs are
contained in the storey; spaces (block models only) are aggregated under it; stair flights are
aggregated under their stair; openings void their host wall and are filled by their door (or by nothing:
``FloorPlan.openings``); with ``FloorPlan.with_slab`` a floor slab (IfcSlab) lies under every cell.

Placement conventions (all placements are IfcLocalPlacement with axis-aligned IfcAxis2Placement3D):

- **Wall**: origin on the wall centre line at the start of the wall, extended by half the thickness
  (so corners and T-junctions close), local X along the wall (+x or +y of the storey), body = the
  rectangle ``[0, L] x [-t/2, t/2]`` extruded 3.0 m; an "Axis" representation follows the centre line.
- **Door**: origin at the centre of the door's footprint at floor level (on the wall centre line),
  local X along the wall, local Y perpendicular to the wall pointing to the circulation side
  (corridor/lobby), Z up. Body = box ``[-W/2, W/2] x [-t/2, t/2] x [0, H]``: exactly the door's
  width, the full wall thickness and its height. The door is placed relative to its opening,
  which has the same frame (relative placement = identity) and a box 0.1 m deeper than the wall.
- **Lift car** (IfcTransportElement ELEVATOR): origin at the shaft centre, local X along the wall
  of the landing door. **Stair**: origin at the foot of the flight (centre of the bottom nosing
  line), local X in the climbing direction; its flight is placed at the same frame.

Geometry is computed with exact axis-aligned arithmetic (no matrix inversion), and every set-valued
relationship attribute is sorted by entity id, so the output is byte-identical from run to run.
GlobalIds are derived from the model name and the entity's position in the file.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass
from typing import Any, Literal

import ifcopenshell
import ifcopenshell.api.aggregate
import ifcopenshell.api.context
import ifcopenshell.api.feature
import ifcopenshell.api.geometry
import ifcopenshell.api.project
import ifcopenshell.api.pset
import ifcopenshell.api.root
import ifcopenshell.api.spatial
import ifcopenshell.api.type
import ifcopenshell.api.unit
import ifcopenshell.guid
import ifcopenshell.ifcopenshell_wrapper as wrapper

from bimtools.samples.layouts import (
    STOREY_ELEVATION,
    STOREY_HEIGHT,
    STOREY_NAME,
    WALL_THICKNESS,
    Cell,
    DoorSpec,
    FloorPlan,
    LiftSpec,
    StairSpec,
    WallPiece,
    host_wall,
    round_um,
    wall_pieces,
)

GUID_NAMESPACE = uuid.UUID("6f9d1c52-3b0e-4d8a-9a57-2c1e8b7f4a10")
HEADER_TIMESTAMP = "2024-01-01T00:00:00"
APPLICATION = "bimtools.samples"
OPENING_EXTRA_DEPTH = 0.1  # openings stick out 5 cm on both wall faces
SLAB_THICKNESS = 0.2  # m: a floor slab (FloorPlan.with_slab), its top at the storey's floor

Entity = ifcopenshell.entity_instance

# Door type per role: (type name, IfcDoorTypeOperationEnum).
DOOR_TYPES: dict[str, tuple[str, str]] = {
    "room": ("Single leaf door 900 x 2100", "SINGLE_SWING_LEFT"),
    "gate": ("Unit main gate 1000 x 2100", "SINGLE_SWING_RIGHT"),
    "lift": ("Lift landing door 1100 x 2100", "DOUBLE_DOOR_SLIDING"),
    "stair": ("Fire door 1200 x 2100", "SINGLE_SWING_LEFT"),
    "exit": ("Exit door 1200 x 2100", "DOUBLE_DOOR_SINGLE_SWING"),
}


@dataclass(frozen=True)
class Frame:
    """A placement in the storey frame: origin and an axis-aligned local X direction about +Z."""

    x: float
    y: float
    z: float = 0.0
    dx: float = 1.0
    dy: float = 0.0

    def relative_to(self, parent: Frame) -> Frame:
        """This frame expressed in ``parent``'s frame (exact for axis-aligned directions)."""
        ox, oy = self.x - parent.x, self.y - parent.y
        c, s = parent.dx, parent.dy
        return Frame(
            x=round_um(c * ox + s * oy),
            y=round_um(-s * ox + c * oy),
            z=round_um(self.z - parent.z),
            dx=round_um(c * self.dx + s * self.dy),
            dy=round_um(-s * self.dx + c * self.dy),
        )


@dataclass
class WrittenModel:
    model: ifcopenshell.file
    doors: dict[str, Entity]  # door tag -> IfcDoor

    def door_guids(self) -> dict[str, str]:
        return {tag: door.GlobalId for tag, door in self.doors.items()}


class _Writer:
    def __init__(self, plan: FloorPlan) -> None:
        self.plan = plan
        self.model = ifcopenshell.api.project.create_file(version="IFC4")
        self.frames: dict[int, Frame] = {}  # entity id -> its frame in the storey
        self.doors: dict[str, Entity] = {}
        self.walls: dict[WallPiece, Entity] = {}
        self.door_types: dict[str, Entity] = {}
        self._origin3 = self.model.createIfcCartesianPoint((0.0, 0.0, 0.0))
        self._origin2 = self.model.createIfcAxis2Placement2D(self.model.createIfcCartesianPoint((0.0, 0.0)))
        self._up = self.model.createIfcDirection((0.0, 0.0, 1.0))

    # ---- top level ------------------------------------------------------------------------

    def write(self) -> WrittenModel:
        self._set_header()
        self._create_project()
        self._create_spatial_tree()
        self._create_door_types()
        walls = wall_pieces(self.plan)
        for i, piece in enumerate(walls, start=1):
            self.walls[piece] = self._create_wall(i, piece)
        for door in self.plan.doors:
            self.doors[door.tag] = self._create_door(door, self.walls[host_wall(self.plan, door, walls)])
        for opening in self.plan.openings:
            self._create_opening(opening, self.walls[host_wall(self.plan, opening, walls)])
        for lift in self.plan.lifts:
            self._create_lift(lift)
        for stair in self.plan.stairs:
            self._create_stair(stair)
        if self.plan.with_spaces:
            for cell in self.plan.cells:
                self._create_space(cell)
        if self.plan.with_slab:
            for cell in self.plan.cells:
                self._create_slab(cell)
        self._sort_set_attributes()
        self._assign_global_ids()
        return WrittenModel(self.model, self.doors)

    def _set_header(self) -> None:
        name = self.model.header.file_name
        name.name = f"{self.plan.name}.ifc"
        name.time_stamp = HEADER_TIMESTAMP
        name.author = ("bim-init",)
        name.organization = ("bim-init",)
        name.preprocessor_version = "IfcOpenShell"
        name.originating_system = APPLICATION
        name.authorization = "none"

    def _create_project(self) -> None:
        api = ifcopenshell.api
        self.project = api.root.create_entity(self.model, ifc_class="IfcProject", name=self.plan.title)
        units = [
            api.unit.add_si_unit(self.model, unit_type=t)
            for t in ("LENGTHUNIT", "AREAUNIT", "VOLUMEUNIT", "PLANEANGLEUNIT")
        ]
        api.unit.assign_unit(self.model, units=units)
        model3d = api.context.add_context(self.model, context_type="Model")
        self.body = self._subcontext(model3d, "Body", "MODEL_VIEW")
        self.axis = self._subcontext(model3d, "Axis", "GRAPH_VIEW")

    def _subcontext(
        self, parent: Entity, identifier: Literal["Body", "Axis"], view: Literal["MODEL_VIEW", "GRAPH_VIEW"]
    ) -> Entity:
        return ifcopenshell.api.context.add_context(
            self.model, context_type="Model", context_identifier=identifier, target_view=view, parent=parent
        )

    def _create_spatial_tree(self) -> None:
        api = ifcopenshell.api
        site = api.root.create_entity(self.model, ifc_class="IfcSite", name="Site")
        building = api.root.create_entity(self.model, ifc_class="IfcBuilding", name=self.plan.building)
        self.storey = api.root.create_entity(self.model, ifc_class="IfcBuildingStorey", name=STOREY_NAME)
        self.storey.Elevation = STOREY_ELEVATION
        api.aggregate.assign_object(self.model, products=[site], relating_object=self.project)
        api.aggregate.assign_object(self.model, products=[building], relating_object=site)
        api.aggregate.assign_object(self.model, products=[self.storey], relating_object=building)
        parent = None
        for element in (site, building, self.storey):
            element.CompositionType = "ELEMENT"
            parent = self._place(element, Frame(0.0, 0.0, 0.0), parent)
        qto = api.pset.add_qto(self.model, product=self.storey, name="Qto_BuildingStoreyBaseQuantities")
        heights: dict[str, Any] = {"GrossHeight": STOREY_HEIGHT, "NetHeight": STOREY_HEIGHT}
        api.pset.edit_qto(self.model, qto=qto, properties=heights)

    def _create_door_types(self) -> None:
        roles = sorted({d.role for d in self.plan.doors}, key=list(DOOR_TYPES).index)
        for role in roles:
            name, operation = DOOR_TYPES[role]
            door_type = ifcopenshell.api.root.create_entity(
                self.model, ifc_class="IfcDoorType", name=name, predefined_type="DOOR"
            )
            door_type.OperationType = operation
            door_type.ParameterTakesPrecedence = False
            ifcopenshell.api.project.assign_declaration(
                self.model, definitions=[door_type], relating_context=self.project
            )
            self.door_types[role] = door_type

    # ---- elements -------------------------------------------------------------------------

    def _contain(self, element: Entity) -> None:
        ifcopenshell.api.spatial.assign_container(
            self.model, products=[element], relating_structure=self.storey
        )

    def _create_wall(self, index: int, piece: WallPiece) -> Entity:
        half = WALL_THICKNESS / 2
        length = round_um(piece.length + WALL_THICKNESS)
        wall = ifcopenshell.api.root.create_entity(
            self.model, ifc_class="IfcWall", name=f"Wall {index:03d}", predefined_type="SOLIDWALL"
        )
        wall.ObjectType = "Generic wall 200"
        self._contain(wall)
        start = piece.point(-half)
        direction = (1.0, 0.0) if piece.axis == "x" else (0.0, 1.0)
        self._place(wall, Frame(start[0], start[1], 0.0, *direction), self.storey)
        body = ifcopenshell.api.geometry.add_wall_representation(
            self.model,
            context=self.body,
            length=length,
            height=STOREY_HEIGHT,
            thickness=WALL_THICKNESS,
            offset=-half,
        )
        axis = ifcopenshell.api.geometry.add_axis_representation(
            self.model, context=self.axis, axis=((0.0, 0.0), (length, 0.0))
        )
        for rep in (axis, body):
            ifcopenshell.api.geometry.assign_representation(self.model, product=wall, representation=rep)
        self._add_pset(wall, "Pset_WallCommon", {"IsExternal": piece.external, "LoadBearing": False})
        return wall

    def _create_opening(self, spec: DoorSpec, wall: Entity) -> Entity:
        """An opening of ``spec``'s width and height through ``wall`` (a door's, or one no door fills)."""
        api = ifcopenshell.api
        frame = Frame(spec.x, spec.y, 0.0, float(spec.along[0]), float(spec.along[1]))
        opening = api.root.create_entity(
            self.model, ifc_class="IfcOpeningElement", name=f"Opening {spec.tag}", predefined_type="OPENING"
        )
        api.feature.add_feature(self.model, feature=opening, element=wall)
        self._place(opening, frame, wall)
        depth = round_um(WALL_THICKNESS + OPENING_EXTRA_DEPTH)
        self._assign_body(opening, self._box(spec.width, depth, spec.height))
        return opening

    def _create_door(self, spec: DoorSpec, wall: Entity) -> Entity:
        api = ifcopenshell.api
        frame = Frame(spec.x, spec.y, 0.0, float(spec.along[0]), float(spec.along[1]))
        opening = self._create_opening(spec, wall)

        door = api.root.create_entity(self.model, ifc_class="IfcDoor", name=spec.name, predefined_type="DOOR")
        door.Tag = spec.tag
        door.OverallWidth = spec.width
        door.OverallHeight = spec.height
        door.OperationType = DOOR_TYPES[spec.role][1]
        api.feature.add_filling(self.model, opening=opening, element=door)
        self._contain(door)
        api.type.assign_type(self.model, related_objects=[door], relating_type=self.door_types[spec.role])
        self._place(door, frame, opening)
        self._assign_body(door, self._box(spec.width, WALL_THICKNESS, spec.height))
        props: dict[str, object] = {"IsExternal": spec.role == "exit", "Reference": DOOR_TYPES[spec.role][0]}
        if spec.role in ("stair", "exit"):
            props["FireRating"] = "FD60"
        self._add_pset(door, "Pset_DoorCommon", props)
        return door

    def _create_lift(self, spec: LiftSpec) -> Entity:
        shaft = self.plan.cell(spec.shaft)
        along = self.plan.door(spec.landing_door).along
        car = ifcopenshell.api.root.create_entity(
            self.model, ifc_class="IfcTransportElement", name=spec.name, predefined_type="ELEVATOR"
        )
        car.ObjectType = "Passenger lift car"
        self._contain(car)
        self._place(car, Frame(*shaft.centre, 0.0, float(along[0]), float(along[1])), self.storey)
        self._assign_body(car, self._box(spec.car_width, spec.car_depth, spec.car_height))
        return car

    def _create_stair(self, spec: StairSpec) -> Entity:
        api = ifcopenshell.api
        frame = Frame(spec.start[0], spec.start[1], 0.0, float(spec.direction[0]), float(spec.direction[1]))
        stair = api.root.create_entity(
            self.model, ifc_class="IfcStair", name=spec.name, predefined_type="STRAIGHT_RUN_STAIR"
        )
        self._contain(stair)
        self._place(stair, frame, self.storey)
        flight = api.root.create_entity(
            self.model, ifc_class="IfcStairFlight", name=f"{spec.name} flight", predefined_type="STRAIGHT"
        )
        api.aggregate.assign_object(self.model, products=[flight], relating_object=stair)
        self._place(flight, frame, stair)
        flight.NumberOfRisers = spec.risers
        flight.NumberOfTreads = spec.risers
        flight.RiserHeight = round_um(spec.riser_height)
        flight.TreadLength = spec.going
        self._assign_body(flight, self._stepped_solid(spec))
        return stair

    def _create_space(self, cell: Cell) -> Entity:
        space = ifcopenshell.api.root.create_entity(
            self.model, ifc_class="IfcSpace", name=cell.name, predefined_type="INTERNAL"
        )
        space.LongName = cell.long_name or cell.name
        space.CompositionType = "ELEMENT"
        ifcopenshell.api.aggregate.assign_object(self.model, products=[space], relating_object=self.storey)
        self._place(space, Frame(*cell.centre, 0.0), self.storey)
        width, depth = cell.size
        self._assign_body(space, self._box(width, depth, STOREY_HEIGHT))
        return space

    def _create_slab(self, cell: Cell) -> Entity:
        """A floor slab under ``cell`` (to its wall centre lines), its top at the storey's floor."""
        slab = ifcopenshell.api.root.create_entity(
            self.model, ifc_class="IfcSlab", name=f"Floor {cell.name}", predefined_type="FLOOR"
        )
        self._contain(slab)
        self._place(slab, Frame(*cell.centre, -SLAB_THICKNESS), self.storey)
        width, depth = cell.size
        self._assign_body(slab, self._box(width, depth, SLAB_THICKNESS))
        return slab

    # ---- geometry and placement helpers ---------------------------------------------------

    def _place(self, product: Entity, frame: Frame, parent: Entity | None) -> Entity:
        """Give ``product`` a local placement at ``frame`` (storey coordinates) relative to ``parent``."""
        parent_placement = parent.ObjectPlacement if parent is not None else None
        local = frame.relative_to(self.frames[parent.id()]) if parent is not None else frame
        location = (
            self._origin3
            if (local.x, local.y, local.z) == (0.0, 0.0, 0.0)
            else self.model.createIfcCartesianPoint((local.x, local.y, local.z))
        )
        if (local.dx, local.dy) == (1.0, 0.0):
            axes = self.model.createIfcAxis2Placement3D(location, None, None)
        else:
            ref = self.model.createIfcDirection((local.dx, local.dy, 0.0))
            axes = self.model.createIfcAxis2Placement3D(location, self._up, ref)
        product.ObjectPlacement = self.model.createIfcLocalPlacement(parent_placement, axes)
        self.frames[product.id()] = frame
        return product

    def _box(self, width: float, depth: float, height: float) -> Entity:
        """A box centred on the local origin in X and Y, from z = 0 to ``height``."""
        profile = self.model.createIfcRectangleProfileDef("AREA", None, self._origin2, width, depth)
        position = self.model.createIfcAxis2Placement3D(self._origin3, None, None)
        return self.model.createIfcExtrudedAreaSolid(profile, position, self._up, height)

    def _stepped_solid(self, spec: StairSpec) -> Entity:
        """The flight as a stepped block: its side profile in the local XZ plane, extruded across."""
        rise, going = spec.riser_height, spec.going
        points = [(0.0, 0.0)]
        for i in range(spec.risers):
            points += [
                (round_um(i * going), round_um((i + 1) * rise)),
                (round_um((i + 1) * going), round_um((i + 1) * rise)),
            ]
        points += [(spec.run, 0.0), (0.0, 0.0)]
        point_list = self.model.createIfcCartesianPointList2D(points)
        curve = self.model.createIfcIndexedPolyCurve(point_list, None, False)
        profile = self.model.createIfcArbitraryClosedProfileDef("AREA", f"{spec.name} side profile", curve)
        # Profile X = climb direction, profile Y = up; extrude along -Y of the flight by its width.
        position = self.model.createIfcAxis2Placement3D(
            self.model.createIfcCartesianPoint((0.0, round_um(spec.width / 2), 0.0)),
            self.model.createIfcDirection((0.0, -1.0, 0.0)),
            self.model.createIfcDirection((1.0, 0.0, 0.0)),
        )
        return self.model.createIfcExtrudedAreaSolid(profile, position, self._up, spec.width)

    def _assign_body(self, product: Entity, solid: Entity) -> None:
        kind = "SweptSolid"
        rep = self.model.createIfcShapeRepresentation(self.body, "Body", kind, [solid])
        ifcopenshell.api.geometry.assign_representation(self.model, product=product, representation=rep)

    def _add_pset(self, product: Entity, name: str, properties: dict[str, object]) -> None:
        pset = ifcopenshell.api.pset.add_pset(self.model, product=product, name=name)
        ifcopenshell.api.pset.edit_pset(self.model, pset=pset, properties=properties)

    # ---- determinism ----------------------------------------------------------------------

    def _sort_set_attributes(self) -> None:
        """Order every SET of entities by entity id (the API builds them from Python sets)."""
        schema = wrapper.schema_by_name(self.model.schema)
        cache: dict[str, list[str]] = {}
        for entity in self.model:
            cls = entity.is_a()
            if cls not in cache:
                declaration = schema.declaration_by_name(cls)
                if not isinstance(declaration, wrapper.entity):
                    raise TypeError(f"{cls} is not an entity of {self.model.schema}")
                cache[cls] = _set_attributes(declaration)
            for attr in cache[cls]:
                value = getattr(entity, attr)
                if value and all(isinstance(v, ifcopenshell.entity_instance) for v in value):
                    setattr(entity, attr, sorted(value, key=lambda e: e.id()))

    def _assign_global_ids(self) -> None:
        """GlobalId = uuid5(namespace, "<model>/<n>") for the n-th rooted entity in file order."""
        rooted = sorted(self.model.by_type("IfcRoot"), key=lambda e: e.id())
        for n, entity in enumerate(rooted, start=1):
            key = uuid.uuid5(GUID_NAMESPACE, f"{self.plan.name}/{n}")
            entity.GlobalId = ifcopenshell.guid.compress(key.hex)


def _set_attributes(declaration: wrapper.entity) -> list[str]:
    names = []
    for attribute in declaration.all_attributes():
        kind = attribute.type_of_attribute()
        if isinstance(kind, wrapper.aggregation_type) and kind.type_of_aggregation_string() == "set":
            names.append(attribute.name())
    return names


def write_model(plan: FloorPlan) -> WrittenModel:
    """Build the IFC model of ``plan`` in memory."""
    return _Writer(plan).write()


__all__ = ["DOOR_TYPES", "Frame", "WrittenModel", "write_model"]
