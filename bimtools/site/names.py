"""Storey names in file names: the one rule ``bim-extract`` (``map_<slug>``, ``preview_<slug>``),
``bim-init survey`` (``survey_<slug>.png``) and everything else that names a file after a storey use.

The rule: NFC-normalise the name; keep Unicode letters and digits (``str.isalnum``) and ``-`` (so that
"Level -1" and "Level 1" stay apart); turn every other run of characters into one ``_``; strip ``_``
from both ends; cut to :data:`MAX_SLUG` characters. A name left with nothing is ``storey_<hash>``
(8 hex digits of the name's SHA-1: stable, and distinct for distinct names). Among the storeys of one
building, a slug already taken gets ``_2``, ``_3``, ... (:func:`storey_slugs`).

Folders written by an older rule still load: ``site.json`` records each storey's map and preview
file, and readers open those, never a name computed again.
"""

from __future__ import annotations

import hashlib
import re
import unicodedata
from collections.abc import Iterable

__all__ = ["MAX_SLUG", "storey_slug", "storey_slugs"]

MAX_SLUG = 64  # characters; 3 bytes each at most in UTF-8, well inside a 255-byte file name

_KEEP = "-"


def storey_slug(name: str) -> str:
    """A file-name-safe form of one storey name (``Уровень 1`` -> ``Уровень_1``)."""
    text = unicodedata.normalize("NFC", name)
    slug = "".join(c if c.isalnum() or c in _KEEP else "_" for c in text)
    slug = re.sub(r"_+", "_", slug).strip("_")[:MAX_SLUG].strip("_")
    if not slug.strip("-"):
        digest = hashlib.sha1(name.encode("utf-8", "surrogatepass")).hexdigest()[:8]
        return f"storey_{digest}"
    return slug


def storey_slugs(names: Iterable[str]) -> list[str]:
    """The slugs of a building's storeys, in order, each distinct: a taken one gets ``_2``, ``_3``..."""
    used: set[str] = set()
    out: list[str] = []
    for name in names:
        base = storey_slug(name)
        slug, k = base, 1
        while slug.casefold() in used:  # case-insensitive file systems: Level_1 and level_1 collide
            k += 1
            slug = f"{base}_{k}"
        used.add(slug.casefold())
        out.append(slug)
    return out
