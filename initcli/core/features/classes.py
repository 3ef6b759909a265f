"""Detector class names <-> BIM feature categories.

Both sides are reduced to a *canonical class*: lower case, surrounding blanks removed, then the
built-in synonyms below, then the site's own mapping ``{"detector name": "Category", ...}``
(``detector.classes`` of the site folder's ``site.yaml``, or ``"classes"`` in its ``site.json``;
see :func:`initcli.match.pipeline.site_class_map`). So ``Door``, ``doors`` and ``DOOR`` all
match features.csv category ``Doors`` (the paper's Table 1) or ``Door`` (bim-extract), and a
detector's ``elevator`` matches category ``Lift``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

__all__ = ["BUILTIN_CLASSES", "BUILTIN_SYNONYMS", "ClassMap"]

BUILTIN_SYNONYMS: dict[str, str] = {
    "door": "door",
    "doors": "door",
    "lift": "lift",
    "lifts": "lift",
    "elevator": "lift",
    "elevators": "lift",
    "stairs": "stairs",
    "stair": "stairs",
    "staircase": "stairs",
    "staircases": "stairs",
    "stairway": "stairs",
}
BUILTIN_CLASSES = ("door", "lift", "stairs")


class ClassMap:
    """Canonicalises class names; ``extra`` maps further names (any case) to a category or class."""

    def __init__(self, extra: Mapping[str, str] | None = None) -> None:
        self.extra = {str(k).strip().lower(): str(v).strip().lower() for k, v in (extra or {}).items()}

    def canonical(self, name: str) -> str:
        key = str(name).strip().lower()
        key = self.extra.get(key, key)
        return BUILTIN_SYNONYMS.get(key, key)

    def known(self, categories: Iterable[str]) -> set[str]:
        """Canonical classes that can be matched: built-ins, the site's categories and mapped names."""
        known = set(BUILTIN_CLASSES)
        known.update(self.canonical(c) for c in categories)
        known.update(BUILTIN_SYNONYMS.get(v, v) for v in self.extra.values())
        return known
