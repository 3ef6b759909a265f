"""bimtools.ifc.text: the words an element is matched by, its predefined type and display name."""

from __future__ import annotations

import ifcopenshell
import ifcopenshell.api.root
import ifcopenshell.api.type

from bimtools.ifc.text import element_name, element_text, predefined_type


def _model() -> ifcopenshell.file:
    return ifcopenshell.file(schema="IFC4")


def test_element_text_joins_element_and_type_words() -> None:
    model = _model()
    door = ifcopenshell.api.root.create_entity(model, ifc_class="IfcDoor", name="D-101")
    door.ObjectType = "Main gate"
    door.Tag = "T7"
    door_type = ifcopenshell.api.root.create_entity(model, ifc_class="IfcDoorType", name="Fire door")
    door_type.Description = "EI60"
    ifcopenshell.api.type.assign_type(model, related_objects=[door], relating_type=door_type)
    assert element_text(door) == "D-101 | Main gate | T7 | Fire door | EI60"


def test_element_text_skips_empty_attributes() -> None:
    model = _model()
    wall = ifcopenshell.api.root.create_entity(model, ifc_class="IfcWall", name="")
    assert element_text(wall) == ""
    space = ifcopenshell.api.root.create_entity(model, ifc_class="IfcSpace", name="101")
    space.LongName = "Lobby"
    assert element_text(space) == "101 | Lobby"


def test_predefined_type_falls_back_to_the_type_then_to_object_type() -> None:
    model = _model()
    lift = ifcopenshell.api.root.create_entity(
        model, ifc_class="IfcTransportElement", predefined_type="ELEVATOR"
    )
    assert predefined_type(lift) == "ELEVATOR"
    untyped = ifcopenshell.api.root.create_entity(model, ifc_class="IfcTransportElement")
    untyped.PredefinedType = "NOTDEFINED"
    lift_type = ifcopenshell.api.root.create_entity(
        model, ifc_class="IfcTransportElementType", predefined_type="ELEVATOR"
    )
    ifcopenshell.api.type.assign_type(model, related_objects=[untyped], relating_type=lift_type)
    assert predefined_type(untyped) == "ELEVATOR"
    custom = ifcopenshell.api.root.create_entity(model, ifc_class="IfcTransportElement")
    custom.PredefinedType = "USERDEFINED"
    custom.ObjectType = "Goods lift"
    assert predefined_type(custom) == "Goods lift"
    wall = ifcopenshell.api.root.create_entity(model, ifc_class="IfcWall")
    assert predefined_type(wall) == ""


def test_element_name_adds_a_different_long_name() -> None:
    model = _model()
    space = ifcopenshell.api.root.create_entity(model, ifc_class="IfcSpace", name="101")
    assert element_name(space) == "101"
    space.LongName = "Lobby"
    assert element_name(space) == "101 Lobby"
    space.LongName = "101"
    assert element_name(space) == "101"
    space.Name = None
    space.LongName = "Lobby"
    assert element_name(space) == "Lobby"
