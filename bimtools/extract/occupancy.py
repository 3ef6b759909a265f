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

from bimtools.extract.floorplan import FloorPlan
from bimtools.extract.section import polygons_of
from bimtools.site.occupancy_map import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

_SHIFT = 4  # sub-pixel bits for cv2 drawing
_MARGIN = 1.0  # metres of unknown around the outline


class GridFrame:
    """World <-> pixel transform of a grid whose row 0 is at the top."""

    def __init__(self, bounds: tuple[float, float, float, float], resolution: float):
        minx, miny, maxx, maxy = bounds
        self.resolution = resolution
        self.origin = (math.floor((minx - _MARGIN) / resolution) * resolution,
                       math.floor((miny - _MARGIN) / resolution) * resolution)
        self.cols = int(math.ceil((maxx + _MARGIN - self.origin[0]) / resolution))
        self.rows = int(math.ceil((maxy + _MARGIN - self.origin[1]) / resolution))

    def to_pixels(self, coords: np.ndarray) -> np.ndarray:
        """World (n, 2) -> fixed-point pixel coordinates (x right, y down) for cv2."""
        px = (coords[:, 0] - self.origin[0]) / self.resolution
        py = self.rows - (coords[:, 1] - self.origin[1]) / self.resolution
        return np.round(np.stack([px, py], axis=1) * (1 << _SHIFT) - 0.5 * (1 << _SHIFT)).astype(np.int32)

    def blank(self, value: int) -> np.ndarray:
        return np.full((self.rows, self.cols), value, dtype=np.uint8)


def _rings(geometry: BaseGeometry, frame: GridFrame) -> tuple[list[np.ndarray], list[np.ndarray]]:
    exteriors, holes = [], []
    for poly in polygons_of(geometry):
        exteriors.append(frame.to_pixels(np.asarray(poly.exterior.coords)[:, :2]))
        holes.extend(frame.to_pixels(np.asarray(r.coords)[:, :2]) for r in poly.interiors)
    return exteriors, holes


def fill(cells: np.ndarray, geometry: BaseGeometry, frame: GridFrame, value: int) -> None:
    """Fill a polygonal area (holes left as they were)."""
    exteriors, holes = _rings(geometry, frame)
    if not exteriors:
        return
    mask = np.zeros_like(cells)
    cv2.fillPoly(mask, exteriors, 1, lineType=cv2.LINE_8, shift=_SHIFT)
    if holes:
        cv2.fillPoly(mask, holes, 0, lineType=cv2.LINE_8, shift=_SHIFT)
    cells[mask == 1] = value


def outline(cells: np.ndarray, geometry: BaseGeometry, frame: GridFrame, value: int) -> None:
    exteriors, holes = _rings(geometry, frame)
    if exteriors or holes:
        cv2.polylines(cells, exteriors + holes, True, value, thickness=1, lineType=cv2.LINE_8, shift=_SHIFT)


def rasterise(plan: FloorPlan, resolution: float) -> tuple[OccupancyGrid, GridFrame]:
    extent = plan.outline if not plan.outline.is_empty else plan.solid
    frame = GridFrame(extent.bounds if not extent.is_empty else (0.0, 0.0, 1.0, 1.0), resolution)
    cells = frame.blank(UNKNOWN)
    fill(cells, plan.outline, frame, FREE)
    fill(cells, plan.solid, frame, UNKNOWN)
    outline(cells, plan.solid, frame, OCCUPIED)
    grid = OccupancyGrid(cells=cells, resolution=resolution, origin=(frame.origin[0], frame.origin[1], 0.0))
    return grid, frame
