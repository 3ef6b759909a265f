"""The words an element is known by: name, object type, type name, description, long name."""

from __future__ import annotations

import ifcopenshell
import ifcopenshell.util.element

__all__ = ["element_name", "element_text", "predefined_type"]


def element_text(element: ifcopenshell.entity_instance) -> str:
    """Everything a category regex is matched against, joined with ' | '."""
    parts: list[str] = []
    for attr in ("Name", "LongName", "ObjectType", "Description", "Tag"):
        value = getattr(element, attr, None)
        if isinstance(value, str) and value:
            parts.append(value)
    element_type = ifcopenshell.util.element.get_type(element)
    if element_type is not None:
        for attr in ("Name", "ElementType", "Description"):
            value = getattr(element_type, attr, None)
            if isinstance(value, str) and value:
                parts.append(value)
    return " | ".join(parts)


def predefined_type(element: ifcopenshell.entity_instance) -> str:
    value = getattr(element, "PredefinedType", None)
    if value in (None, "NOTDEFINED", "USERDEFINED"):
        element_type = ifcopenshell.util.element.get_type(element)
        value = getattr(element_type, "PredefinedType", None) if element_type is not None else value
    if value == "USERDEFINED":
        value = getattr(element, "ObjectType", None) or value
    return str(value or "")


def element_name(element: ifcopenshell.entity_instance) -> str:
    name = getattr(element, "Name", None) or ""
    long_name = getattr(element, "LongName", None) or ""
    if long_name and long_name != name:
        return f"{name} {long_name}".strip()
    return name
