"""``bim-extract MAP.yaml``: any ROS map_server / Nav2 map is a site.

The site has one storey named after the YAML's stem, at elevation 0: the map as given (read by
:func:`bimtools.site.occupancy_map.read_map`, unknown cells stay unknown), walls from the occupied
cells and no features (``features.csv`` holds its header only) unless ``--features FILE.csv``
gives them in the paper's Table 1 columns. Everything is written in the layout of an IFC
extraction (:mod:`bimtools.extract.output`), so ``bim-init`` reads it the same way.

Walls: every side of an occupied cell that faces a free cell is a wall surface, joined along a
row or column into one segment per straight run, its normal pointing into the free cell (sides
facing unknown cells or the map's edge are no surface a robot sees). Obstacles: the outlines of
the occupied cells, one per connected piece (what the simulator's world is built of).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from bimkit.atomic import staged_directory
from bimkit.checks import read_bytes
from bimkit.errors import InputError
from bimkit.limits import MAX_MAP_BYTES, MAX_TEXT_BYTES
from bimtools import __version__
from bimtools.ifc.storeys import storey_slug
from bimtools.settings import DEFAULT_SECTION_HEIGHT
from bimtools.site.features_csv import read_feature_rows, write_features
from bimtools.site.manifest import SiteManifest, format_manifest
from bimtools.site.occupancy_map import map_image_path, read_map, write_map
from bimtools.site.records import (
    FREE,
    LANDMARK_CATEGORIES,
    OCCUPIED,
    Feature,
    Obstacle,
    OccupancyGrid,
    StoreyInfo,
    WallSegment,
)
from bimtools.site.walls_geojson import write_walls

__all__ = [
    "MAP_CLASS",
    "MAP_SCHEMA",
    "MapSite",
    "extract_map_site",
    "grid_obstacles",
    "grid_walls",
    "is_map_file",
    "read_map_features",
    "read_map_site",
    "trace_map_site",
    "write_map_site",
]

MAP_SCHEMA = "NAV2_MAP"  # site.json "schema" of a site made from a map
MAP_CLASS = "OccupiedCells"  # ifc_class of the walls and obstacles a map's occupied cells make
MAP_SUFFIXES = (".yaml", ".yml")


def is_map_file(path: Path) -> bool:
    """A map YAML: by its suffix, or (any other name) by a first line that is no IFC header and
    ``image:`` and ``resolution:`` keys in its first 4 KiB."""
    path = Path(path)
    if path.suffix.lower() in MAP_SUFFIXES:
        return True
    if not path.is_file():
        return False  # a pipe or a device is never opened to sniff (it could block for ever)
    try:
        with path.open("rb") as handle:
            head = handle.read(4096)
    except OSError:
        return False
    if head.lstrip().startswith(b"ISO-10303-21") or b"\x00" in head:
        return False
    lines = [line.strip() for line in head.splitlines()]
    return any(line.startswith(b"image:") for line in lines) and any(
        line.startswith(b"resolution:") for line in lines
    )


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row, first column, last column) of every run of True along the rows of ``mask``."""
    rows, cols = mask.shape
    padded = np.zeros((rows, cols + 2), dtype=np.int8)
    padded[:, 1:-1] = mask
    step = np.diff(padded, axis=1)
    r0, c0 = np.nonzero(step == 1)
    r1, c1 = np.nonzero(step == -1)  # row-major order: the k-th start and end are one run
    assert np.array_equal(r0, r1)
    return r0, c0, c1 - 1


def _labels(occupied: np.ndarray) -> np.ndarray:
    """The connected piece (8 neighbours) of every occupied cell, numbered from 1."""
    _, labels = cv2.connectedComponents(occupied.astype(np.uint8), connectivity=8, ltype=cv2.CV_32S)
    return np.asarray(labels)


def _element(label: int) -> str:
    return f"occupied-{label}"


def grid_walls(grid: OccupancyGrid, storey: str) -> list[WallSegment]:
    """The wall surfaces of a map: the sides of occupied cells facing free cells, one segment per
    straight run, normal into the free side; ``element`` names the occupied piece."""
    cells = np.asarray(grid.cells)
    occupied, free = cells == OCCUPIED, cells == FREE
    labels = _labels(occupied)
    rows, _ = cells.shape
    res = float(grid.resolution)
    ox, oy = float(grid.origin[0]), float(grid.origin[1])
    shifted = np.zeros_like(free)
    walls: list[WallSegment] = []

    def add(x1: float, y1: float, x2: float, y2: float, normal: tuple[float, float], label: int) -> None:
        walls.append(WallSegment(storey, _element(label), MAP_CLASS, x1, y1, x2, y2, normal))

    # free above (row - 1): the top side of the cell, normal +y; free below: the bottom side, -y
    for dr, ny in ((-1, 1.0), (1, -1.0)):
        shifted[:] = False
        if dr < 0:
            shifted[1:] = free[:-1]
        else:
            shifted[:-1] = free[1:]
        r, c0, c1 = _runs(occupied & shifted)
        for row, first, last in zip(r.tolist(), c0.tolist(), c1.tolist(), strict=True):
            y = oy + (rows - row) * res if ny > 0 else oy + (rows - 1 - row) * res
            add(ox + first * res, y, ox + (last + 1) * res, y, (0.0, ny), int(labels[row, first]))
    # free left (column - 1): the left side, normal -x; free right: the right side, +x
    for dc, nx in ((-1, -1.0), (1, 1.0)):
        shifted[:] = False
        if dc < 0:
            shifted[:, 1:] = free[:, :-1]
        else:
            shifted[:, :-1] = free[:, 1:]
        c, r0, r1 = _runs((occupied & shifted).T)
        for col, first, last in zip(c.tolist(), r0.tolist(), r1.tolist(), strict=True):
            x = ox + col * res if nx < 0 else ox + (col + 1) * res
            add(
                x,
                oy + (rows - 1 - last) * res,
                x,
                oy + (rows - first) * res,
                (nx, 0.0),
                int(labels[first, col]),
            )
    return walls


def _run_boxes(grid: OccupancyGrid) -> tuple[np.ndarray, np.ndarray]:
    """Rectangles (x0, y0, x1, y1) of the runs of occupied cells along the rows, and the piece of each."""
    cells = np.asarray(grid.cells)
    occupied = cells == OCCUPIED
    labels = _labels(occupied)
    rows = cells.shape[0]
    res = float(grid.resolution)
    ox, oy = float(grid.origin[0]), float(grid.origin[1])
    r, c0, c1 = _runs(occupied)
    boxes = np.column_stack(
        [ox + c0 * res, oy + (rows - 1 - r) * res, ox + (c1 + 1) * res, oy + (rows - r) * res]
    ).reshape(-1, 4)
    return boxes, labels[r, c0] if len(r) else np.zeros(0, dtype=np.int32)


def grid_obstacles(grid: OccupancyGrid, storey: str) -> list[Obstacle]:
    """The outlines of the occupied cells, one obstacle per polygon of a connected piece."""
    cells = np.asarray(grid.cells)
    occupied = cells == OCCUPIED
    labels = _labels(occupied)
    r, c0, c1 = _runs(occupied)
    if not len(r):
        return []
    pieces = labels[r, c0]
    # in whole cells (exact: the union meets every shared edge), then to metres
    shapes = shapely.box(c0, -r - 1, c1 + 1, -r)
    rows, res = cells.shape[0], float(grid.resolution)
    ox, oy = float(grid.origin[0]), float(grid.origin[1])
    order = np.argsort(pieces, kind="stable")
    bounds = np.flatnonzero(np.r_[True, pieces[order][1:] != pieces[order][:-1], True])
    obstacles: list[Obstacle] = []
    for a, b in zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=True):
        merged = shapely.simplify(shapely.union_all(shapes[order[a:b]]), 0.0)
        merged = shapely.transform(
            merged, lambda xy: np.column_stack([ox + xy[:, 0] * res, oy + (rows + xy[:, 1]) * res])
        )
        polygons = list(getattr(merged, "geoms", [merged]))
        label = int(pieces[order[a]])
        for poly in polygons:
            if not isinstance(poly, Polygon) or poly.is_empty:
                continue
            exterior = tuple((float(x), float(y)) for x, y in poly.exterior.coords)
            holes = tuple(tuple((float(x), float(y)) for x, y in ring.coords) for ring in poly.interiors)
            obstacles.append(Obstacle(storey, _element(label), MAP_CLASS, exterior, holes))
    return obstacles


def read_map_features(
    path: Path, storey: str, grid: OccupancyGrid, categories: list[str] | tuple[str, ...]
) -> list[Feature]:
    """The features of a Table 1 CSV (the columns of features.csv) for a map's storey: each
    category one of ``categories`` or a landmark category (any case; written as the category is
    spelt there), IDs unique, on the map, a Storey column empty or the storey's name; one line
    naming the file and line otherwise."""
    path = Path(path)
    known = {c.lower(): c for c in (*categories, *LANDMARK_CATEGORIES)}
    rows, cols = grid.shape
    x0, y0 = grid.origin[0], grid.origin[1]
    x1, y1 = x0 + cols * grid.resolution, y0 + rows * grid.resolution
    features: list[Feature] = []
    for line, f in read_feature_rows(path):
        category = known.get(f.category.lower())
        if category is None:
            shown = f.category if len(f.category) <= 40 else f"{f.category[:30]}..."
            raise InputError(
                f"{path}:{line}: column Category: unknown category {shown!r}; known: "
                f"{', '.join(known.values())}"
            )
        if f.storey and f.storey != storey:
            raise InputError(
                f"{path}:{line}: column Storey: {f.storey!r} is not the map's storey {storey!r} "
                "(leave it empty)"
            )
        if not (x0 <= f.x <= x1 and y0 <= f.y <= y1):
            raise InputError(
                f"{path}:{line}: ({f.x:g}, {f.y:g}) lies outside the map "
                f"(x {x0:g}..{x1:g}, y {y0:g}..{y1:g} m)"
            )
        features.append(replace(f, category=category, storey=storey))
    return features


@dataclass
class MapSite:
    """A map read as a site: its one storey's grid, walls, obstacles and features."""

    yaml_path: Path
    image_path: Path
    sha256: str
    storey: str
    grid: OccupancyGrid
    section_height: float = DEFAULT_SECTION_HEIGHT
    features: list[Feature] = field(default_factory=list)
    walls: list[WallSegment] = field(default_factory=list)
    obstacles: list[Obstacle] = field(default_factory=list)

    @property
    def slug(self) -> str:
        return storey_slug(self.storey)


def _sha256(yaml_path: Path, image: Path) -> str:
    """Of the YAML's bytes and then the image's: either changed, the site is another."""
    digest = hashlib.sha256(read_bytes(yaml_path, "a map YAML (ROS map_server)", MAX_TEXT_BYTES))
    digest.update(read_bytes(image, "a map image (PGM or PNG)", MAX_MAP_BYTES))
    return digest.hexdigest()


def read_map_site(
    yaml_path: Path,
    features: Path | None = None,
    categories: list[str] | tuple[str, ...] = ("Door", "Lift", "Stairs"),
    section_height: float = DEFAULT_SECTION_HEIGHT,
) -> MapSite:
    """The map and the features checked (every InputError before any wall is traced)."""
    yaml_path = Path(yaml_path)
    grid = read_map(yaml_path)
    image = map_image_path(yaml_path)
    assert image is not None  # read_map found it
    storey = yaml_path.stem
    site = MapSite(yaml_path, image, _sha256(yaml_path, image), storey, grid, section_height)
    if features is not None:
        site.features = read_map_features(features, storey, grid, categories)
    return site


def extract_map_site(
    yaml_path: Path,
    features: Path | None = None,
    categories: list[str] | tuple[str, ...] = ("Door", "Lift", "Stairs"),
    section_height: float = DEFAULT_SECTION_HEIGHT,
) -> MapSite:
    """:func:`read_map_site`, then the walls and obstacles of its occupied cells."""
    return trace_map_site(read_map_site(yaml_path, features, categories, section_height))


def trace_map_site(site: MapSite) -> MapSite:
    site.walls = grid_walls(site.grid, site.storey)
    site.obstacles = grid_obstacles(site.grid, site.storey)
    return site


def build_map_manifest(site: MapSite, files: list[str]) -> SiteManifest:
    counts: dict[str, int] = {}
    for f in site.features:
        counts[f.category] = counts.get(f.category, 0) + 1
    slug = site.slug
    return SiteManifest(
        source_file=site.yaml_path.name,
        source_sha256=site.sha256,
        schema=MAP_SCHEMA,
        application="",
        length_unit="METRE",
        unit_scale=1.0,
        section_height=site.section_height,
        resolution=site.grid.resolution,
        storeys=[StoreyInfo(site.storey, 0.0, counts, f"map_{slug}.yaml", f"preview_{slug}.png")],
        files=files,
        tool_version=__version__,
    )


def write_map_site(outdir: Path, site: MapSite, preview: bool = True) -> SiteManifest:
    """Write features.csv, walls.geojson, the map, its preview and site.json into ``outdir``,
    staged as :func:`bimtools.extract.output.write_site` does (all or nothing)."""
    from bimtools.extract.output import SITE_MARKERS
    from bimtools.extract.preview import render_preview

    slug = site.slug
    with staged_directory(Path(outdir), SITE_MARKERS) as stage:
        files = ["features.csv", "walls.geojson", f"map_{slug}.pgm", f"map_{slug}.yaml"]
        write_features(stage / "features.csv", site.features)
        write_walls(stage / "walls.geojson", site.walls, site.obstacles)
        write_map(stage / f"map_{slug}.yaml", site.grid)
        if preview:
            boxes, _ = _run_boxes(site.grid)
            rows, cols = site.grid.shape
            x0, y0 = site.grid.origin[0], site.grid.origin[1]
            outline: BaseGeometry = shapely.box(
                x0, y0, x0 + cols * site.grid.resolution, y0 + rows * site.grid.resolution
            )
            render_preview(
                stage / f"preview_{slug}.png",
                f"{site.yaml_path.name} - {site.storey} (a map)",
                list(shapely.box(boxes[:, 0], boxes[:, 1], boxes[:, 2], boxes[:, 3])),
                site.walls,
                site.features,
                outline,
            )
            files.append(f"preview_{slug}.png")
        files.append("site.json")
        manifest = build_map_manifest(site, files)
        (stage / "site.json").write_text(format_manifest(manifest), encoding="utf-8")
    return manifest
