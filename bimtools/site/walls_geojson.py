"""``walls.geojson``: wall surfaces (LineStrings with a free-space normal) and obstacle footprints.

Every feature carries ``storey``, ``element`` (GlobalId) and ``ifc_class``; LineStrings also a
``normal`` [nx, ny] pointing into free space, Polygons ``kind: "obstacle"``. ``glass`` is true
for glazed elements (windows, curtain walls and their panels): they block motion but a lidar
mostly sees through them.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from bimkit.checks import read_json
from bimkit.errors import InputError
from bimtools.site.records import Obstacle, WallSegment

__all__ = ["read_walls", "walls_to_geojson", "write_walls"]


def _r(v: float) -> float:
    return round(float(v), 4)


def walls_to_geojson(walls: Iterable[WallSegment], obstacles: Iterable[Obstacle]) -> dict[str, Any]:
    features: list[dict[str, Any]] = []
    for w in walls:
        features.append(
            {
                "type": "Feature",
                "geometry": {
                    "type": "LineString",
                    "coordinates": [[_r(w.x1), _r(w.y1)], [_r(w.x2), _r(w.y2)]],
                },
                "properties": {
                    "kind": "wall_surface",
                    "storey": w.storey,
                    "element": w.element,
                    "ifc_class": w.ifc_class,
                    "normal": [round(w.normal[0], 6), round(w.normal[1], 6)],
                    "glass": w.glass,
                },
            }
        )
    for o in obstacles:
        rings = [[[_r(x), _r(y)] for x, y in o.exterior]] + [[[_r(x), _r(y)] for x, y in h] for h in o.holes]
        features.append(
            {
                "type": "Feature",
                "geometry": {"type": "Polygon", "coordinates": rings},
                "properties": {
                    "kind": "obstacle",
                    "storey": o.storey,
                    "element": o.element,
                    "ifc_class": o.ifc_class,
                    "glass": o.glass,
                },
            }
        )
    return {"type": "FeatureCollection", "features": features}


def write_walls(path: Path, walls: Iterable[WallSegment], obstacles: Iterable[Obstacle]) -> None:
    Path(path).write_text(
        json.dumps(walls_to_geojson(walls, obstacles), separators=(",", ":")), encoding="utf-8"
    )


def read_walls(path: Path, storey: str | None = None) -> tuple[list[WallSegment], list[Obstacle]]:
    """Read wall surfaces and obstacles, optionally only those of one storey."""
    path = Path(path)
    doc = read_json(path)
    if not isinstance(doc, dict) or doc.get("type") != "FeatureCollection":
        raise InputError(f"{path}: expected a GeoJSON FeatureCollection")
    walls: list[WallSegment] = []
    obstacles: list[Obstacle] = []
    features = doc.get("features", [])
    if not isinstance(features, list):
        raise InputError(f"{path}: features: expected a list")
    for index, feat in enumerate(features):
        try:
            props = feat["properties"]
            geom = feat["geometry"]
            if storey is not None and props.get("storey") != storey:
                continue
            if geom["type"] == "LineString":
                (x1, y1), (x2, y2) = geom["coordinates"][0], geom["coordinates"][-1]
                nx, ny = props["normal"]
                walls.append(
                    WallSegment(
                        props.get("storey", ""),
                        props.get("element", ""),
                        props.get("ifc_class", ""),
                        float(x1),
                        float(y1),
                        float(x2),
                        float(y2),
                        (float(nx), float(ny)),
                        bool(props.get("glass", False)),
                    )
                )
            elif geom["type"] == "Polygon":
                rings = [tuple((float(x), float(y)) for x, y in ring) for ring in geom["coordinates"]]
                obstacles.append(
                    Obstacle(
                        props.get("storey", ""),
                        props.get("element", ""),
                        props.get("ifc_class", ""),
                        rings[0],
                        tuple(rings[1:]),
                        bool(props.get("glass", False)),
                    )
                )
        except (KeyError, TypeError, ValueError, AttributeError, IndexError) as exc:
            raise InputError(f"{path}: features[{index}]: malformed wall or obstacle ({exc!r})") from None
    return walls, obstacles
