"""Rasterise a floor plan into a map_server occupancy grid.

Free inside the building outline, unknown outside it; obstacles are drawn as outlines only
(occupied border, unknown interior), because thick filled walls make likelihood-field particle
filters lose the pose.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from shapely.geometry.base import BaseGeometry

from bimkit.errors import InputError
from bimtools.extract.floorplan import FloorPlan
from bimtools.extract.section import polygons_of
from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

__all__ = ["GridFrame", "MAX_GRID_PIXELS", "fill", "outline", "rasterise"]

MAX_GRID_PIXELS = 10_000 * 10_000  # one storey's occupancy map (100 MB of uint8)

_SHIFT = 4  # sub-pixel bits for cv2 drawing
_MARGIN = 1.0  # metres of unknown around the outline


class GridFrame:
    """World <-> pixel transform of a grid whose row 0 is at the top."""

    def __init__(self, bounds: tuple[float, float, float, float], resolution: float):
        minx, miny, maxx, maxy = bounds
        self.resolution = resolution
        self.origin = (
            math.floor((minx - _MARGIN) / resolution) * resolution,
            math.floor((miny - _MARGIN) / resolution) * resolution,
        )
        self.cols = int(math.ceil((maxx + _MARGIN - self.origin[0]) / resolution))
        self.rows = int(math.ceil((maxy + _MARGIN - self.origin[1]) / resolution))

    def to_pixels(self, coords: np.ndarray) -> np.ndarray:
        """World (n, 2) -> fixed-point pixel coordinates (x right, y down) for cv2."""
        px = (coords[:, 0] - self.origin[0]) / self.resolution
        py = self.rows - (coords[:, 1] - self.origin[1]) / self.resolution
        return np.round(np.stack([px, py], axis=1) * (1 << _SHIFT) - 0.5 * (1 << _SHIFT)).astype(np.int32)

    def blank(self, value: int) -> np.ndarray:
        return np.full((self.rows, self.cols), value, dtype=np.uint8)


def _pixel_rings(poly, frame: GridFrame) -> tuple[np.ndarray, list[np.ndarray]]:
    exterior = frame.to_pixels(np.asarray(poly.exterior.coords)[:, :2])
    holes = [frame.to_pixels(np.asarray(r.coords)[:, :2]) for r in poly.interiors]
    return exterior, holes


def fill(cells: np.ndarray, geometry: BaseGeometry, frame: GridFrame, value: int) -> None:
    """Fill a polygonal area, holes excluded.

    Each polygon is filled on its own: cv2 fills several contours even-odd, which would cancel
    a part standing inside another part's hole (a block of rooms inside a corridor loop).
    """
    for poly in polygons_of(geometry):
        exterior, holes = _pixel_rings(poly, frame)
        x, y, w, h = cv2.boundingRect(exterior >> _SHIFT)
        x0, y0 = max(x - 1, 0), max(y - 1, 0)
        x1, y1 = min(x + w + 2, cells.shape[1]), min(y + h + 2, cells.shape[0])
        if x1 <= x0 or y1 <= y0:
            continue
        offset = np.array([x0, y0], dtype=np.int32) << _SHIFT
        mask = np.zeros((y1 - y0, x1 - x0), dtype=np.uint8)
        cv2.fillPoly(mask, [exterior - offset], 1, lineType=cv2.LINE_8, shift=_SHIFT)
        if holes:
            for hole in holes:
                cv2.fillPoly(mask, [hole - offset], 0, lineType=cv2.LINE_8, shift=_SHIFT)
        cells[y0:y1, x0:x1][mask == 1] = value


def outline(cells: np.ndarray, geometry: BaseGeometry, frame: GridFrame, value: int) -> None:
    rings: list[np.ndarray] = []
    for poly in polygons_of(geometry):
        exterior, holes = _pixel_rings(poly, frame)
        rings += [exterior, *holes]
    if rings:
        cv2.polylines(cells, rings, True, value, thickness=1, lineType=cv2.LINE_8, shift=_SHIFT)


def rasterise(plan: FloorPlan, resolution: float) -> tuple[OccupancyGrid, GridFrame]:
    extent = plan.outline if not plan.outline.is_empty else plan.solid
    frame = GridFrame(extent.bounds if not extent.is_empty else (0.0, 0.0, 1.0, 1.0), resolution)
    if frame.rows * frame.cols > MAX_GRID_PIXELS:
        raise InputError(
            f"storey {plan.storey!r}: the map would be {frame.cols} x {frame.rows} pixels at "
            f"--resolution {resolution:g} (at most {MAX_GRID_PIXELS}); use a coarser --resolution"
        )
    cells = frame.blank(UNKNOWN)
    fill(cells, plan.outline, frame, FREE)
    fill(cells, plan.solid, frame, UNKNOWN)
    outline(cells, plan.solid, frame, OCCUPIED)
    grid = OccupancyGrid(cells=cells, resolution=resolution, origin=(frame.origin[0], frame.origin[1], 0.0))
    return grid, frame
