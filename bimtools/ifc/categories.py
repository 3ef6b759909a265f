"""Feature categories: which IFC elements become Door, Lift, Stairs (or user-defined) features.

The default mapping ships as ``bimtools/default_categories.yaml`` (documented there); users pass
their own with ``bim-extract --categories FILE.yaml``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import ifcopenshell

from bimkit.checks import range_problem, read_yaml
from bimkit.errors import InputError
from bimtools.ifc.text import element_text, predefined_type
from bimtools.settings import LandmarkSettings, parse_landmarks
from bimtools.site.records import LANDMARK_CATEGORIES

__all__ = [
    "Category",
    "CategorySet",
    "DEFAULT_CATEGORIES",
    "ElementRule",
    "KINDS",
    "load_categories",
    "parse_categories",
]

DEFAULT_CATEGORIES = Path(__file__).resolve().parent.parent / "default_categories.yaml"
KINDS = ("door", "lift", "stairs")


@dataclass(frozen=True)
class ElementRule:
    classes: tuple[str, ...] = ()
    predefined_types: tuple[str, ...] = ()
    text: re.Pattern[str] | None = None
    not_text: re.Pattern[str] | None = None

    def matches(self, element: ifcopenshell.entity_instance) -> bool:
        if self.classes and not any(element.is_a(c) for c in self.classes):
            return False
        if self.predefined_types and predefined_type(element).upper() not in self.predefined_types:
            return False
        if self.text is not None or self.not_text is not None:
            words = element_text(element)
            if self.text is not None and not self.text.search(words):
                return False
            if self.not_text is not None and self.not_text.search(words):
                return False
        return True


@dataclass(frozen=True)
class Category:
    name: str
    kind: str
    doors: tuple[ElementRule, ...] = ()
    bodies: tuple[ElementRule, ...] = ()
    spaces: re.Pattern[str] | None = None
    enclosure_max_area: float = 30.0

    def is_door(self, element: ifcopenshell.entity_instance) -> bool:
        return any(rule.matches(element) for rule in self.doors)

    def is_body(self, element: ifcopenshell.entity_instance) -> bool:
        return any(rule.matches(element) for rule in self.bodies)

    def is_space(self, name: str) -> bool:
        return bool(self.spaces and name and self.spaces.search(name))

    @property
    def classes(self) -> set[str]:
        return {c for rule in self.doors + self.bodies for c in rule.classes}


@dataclass(frozen=True)
class CategorySet:
    categories: tuple[Category, ...]
    circulation_spaces: re.Pattern[str] | None = None
    source: str = field(default="default")
    landmarks: LandmarkSettings = field(default_factory=LandmarkSettings)  # the lidar landmarks

    def is_circulation(self, name: str) -> bool:
        return bool(self.circulation_spaces and name and self.circulation_spaces.search(name))

    @property
    def names(self) -> list[str]:
        return [c.name for c in self.categories]


def _regex(value: object, where: str, flags: int = re.IGNORECASE) -> re.Pattern[str] | None:
    if value is None:
        return None
    if not isinstance(value, str):
        raise InputError(f"{where}: expected a regular expression string, got {type(value).__name__}")
    try:
        return re.compile(value, flags)
    except re.error as exc:
        raise InputError(f"{where}: invalid regular expression ({exc})") from None


def _names(value: object, where: str) -> tuple[str, ...]:
    if value is None:
        return ()
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise InputError(f"{where}: expected a list of names")
    return tuple(value)


def _rule(doc: object, where: str) -> ElementRule:
    if not isinstance(doc, dict):
        raise InputError(f"{where}: expected a mapping with classes/predefined_types/text/not_text")
    unknown = set(doc) - {"classes", "predefined_types", "text", "not_text"}
    if unknown:
        raise InputError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}")
    classes = _names(doc.get("classes"), f"{where}.classes")
    for name in classes:
        if not re.fullmatch(r"Ifc[A-Za-z]+", name):
            raise InputError(f"{where}.classes: {name!r} is not an IFC class name")
    if not (classes or doc.get("text") or doc.get("predefined_types")):
        raise InputError(f"{where}: a rule needs at least one of classes, predefined_types, text")
    return ElementRule(
        classes=classes,
        predefined_types=tuple(
            t.upper() for t in _names(doc.get("predefined_types"), f"{where}.predefined_types")
        ),
        text=_regex(doc.get("text"), f"{where}.text"),
        not_text=_regex(doc.get("not_text"), f"{where}.not_text"),
    )


def parse_categories(doc: object, source: str) -> CategorySet:
    if not isinstance(doc, dict):
        raise InputError(f"{source}: expected a mapping with a 'categories' list")
    items = doc.get("categories")
    if not isinstance(items, list) or not items:
        raise InputError(f"{source}: categories: expected a non-empty list")
    categories: list[Category] = []
    for index, item in enumerate(items):
        where = f"{source}: categories[{index}]"
        if not isinstance(item, dict):
            raise InputError(f"{where}: expected a mapping")
        name = item.get("name")
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_ -]*", name):
            raise InputError(f"{where}.name: expected a category name, got {name!r}")
        if name in LANDMARK_CATEGORIES:
            raise InputError(
                f"{where}.name: {name!r} is a lidar landmark category (see the landmarks: block), "
                "not a name for a camera category"
            )
        kind = item.get("kind", "door")
        if kind not in KINDS:
            raise InputError(f"{where}.kind: expected one of {', '.join(KINDS)}, got {kind!r}")
        for key in ("doors", "bodies"):
            if item.get(key) is not None and not isinstance(item.get(key), list):
                raise InputError(f"{where}.{key}: expected a list of rules")
        area = item.get("enclosure_max_area", 30.0)
        problem = range_problem(area, above=0, maximum=1e6)
        if problem is not None:
            raise InputError(f"{where}.enclosure_max_area: {problem} (m^2, (0, 1000000])")
        category = Category(
            name=name,
            kind=kind,
            doors=tuple(_rule(r, f"{where}.doors[{i}]") for i, r in enumerate(item.get("doors") or [])),
            bodies=tuple(_rule(r, f"{where}.bodies[{i}]") for i, r in enumerate(item.get("bodies") or [])),
            spaces=_regex(item.get("spaces"), f"{where}.spaces", 0),
            enclosure_max_area=float(area),
        )
        if not (category.doors or category.bodies or category.spaces):
            raise InputError(f"{where}: needs at least one of doors, bodies, spaces")
        categories.append(category)
    names = [c.name for c in categories]
    duplicates = {n for n in names if names.count(n) > 1}
    if duplicates:
        raise InputError(f"{source}: categories: duplicate name(s) {', '.join(sorted(duplicates))}")
    return CategorySet(
        categories=tuple(categories),
        circulation_spaces=_regex(doc.get("circulation_spaces"), f"{source}: circulation_spaces", 0),
        source=source,
        landmarks=parse_landmarks(doc.get("landmarks"), f"{source}: landmarks"),
    )


def load_categories(path: Path | None = None) -> CategorySet:
    """Read a categories YAML (the shipped default when ``path`` is None)."""
    path = Path(path) if path is not None else DEFAULT_CATEGORIES
    doc = read_yaml(path, "categories file")
    return parse_categories(doc, str(path))
