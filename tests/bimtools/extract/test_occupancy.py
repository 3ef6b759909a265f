"""bimtools.extract.occupancy: the grid frame and the rasterised map of a generated floor plan."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import box

from bimkit.errors import InputError
from bimtools.extract.floorplan import ObstacleShape, build_floorplan
from bimtools.extract.occupancy import MAX_GRID_PIXELS, GridFrame, fill, rasterise
from bimtools.site.records import FREE, OCCUPIED, UNKNOWN


def _cell(grid, frame: GridFrame, x: float, y: float) -> int:
    col = int((x - frame.origin[0]) / frame.resolution)
    row = frame.rows - 1 - int((y - frame.origin[1]) / frame.resolution)
    return int(grid.cells[row, col])


def test_grid_frame_adds_a_metre_margin_on_the_resolution_lattice() -> None:
    frame = GridFrame((0.03, 0.0, 4.0, 2.0), 0.1)
    assert frame.origin[0] == pytest.approx(-1.0)
    assert frame.origin[1] == pytest.approx(-1.0)
    assert frame.cols == 60 and frame.rows == 40
    assert frame.blank(7).shape == (40, 60)
    assert (frame.blank(7) == 7).all()


def test_to_pixels_flips_y_with_row_zero_at_the_top() -> None:
    frame = GridFrame((0.0, 0.0, 4.0, 2.0), 0.1)
    px = frame.to_pixels(np.array([[-1.0, -1.0], [-1.0, 3.0]])) / 16.0
    # the lowest world y is the bottom row, the highest the top row
    assert px[0, 1] > px[1, 1]
    assert px[1, 1] == pytest.approx(-0.5)
    assert px[0, 1] == pytest.approx(frame.rows - 0.5)


def test_fill_keeps_a_block_inside_another_parts_hole() -> None:
    frame = GridFrame((0.0, 0.0, 10.0, 10.0), 0.1)
    cells = frame.blank(0)
    loop = box(0, 0, 10, 10).difference(box(2, 2, 8, 8))
    block = box(4, 4, 6, 6)
    fill(cells, loop.union(block), frame, 1)
    row = lambda y: frame.rows - 1 - int((y - frame.origin[1]) / 0.1)  # noqa: E731
    col = lambda x: int((x - frame.origin[0]) / 0.1)  # noqa: E731
    assert cells[row(1), col(1)] == 1  # in the loop
    assert cells[row(3), col(3)] == 0  # in the hole
    assert cells[row(5), col(5)] == 1  # the block inside the hole is filled too


def test_rasterise_a_room_free_inside_outlined_walls_unknown_outside() -> None:
    t = 0.2
    walls = [
        ObstacleShape("s", "IfcWall", box(-t, -t, 4 + t, 0)),
        ObstacleShape("n", "IfcWall", box(-t, 4, 4 + t, 4 + t)),
        ObstacleShape("w", "IfcWall", box(-t, 0, 0, 4)),
        ObstacleShape("e", "IfcWall", box(4, 0, 4 + t, 4)),
    ]
    plan = build_floorplan("L", 1.0, walls, spaces=[])
    grid, frame = rasterise(plan, 0.05)
    assert grid.resolution == 0.05
    assert grid.origin == (frame.origin[0], frame.origin[1], 0.0)
    assert grid.cells.shape == (frame.rows, frame.cols)
    assert _cell(grid, frame, 2.0, 2.0) == FREE
    assert _cell(grid, frame, -0.6, 2.0) == UNKNOWN  # outside the building
    assert _cell(grid, frame, 2.0, -0.1) == UNKNOWN  # inside a wall: outline only
    column = grid.cells[:, int((2.0 - frame.origin[0]) / frame.resolution)]
    rows = np.flatnonzero(column == OCCUPIED)
    ys = frame.origin[1] + (frame.rows - 1 - rows + 0.5) * frame.resolution
    for face in (-t, 0.0, 4.0, 4 + t):  # both faces of the south and north walls are drawn
        assert np.abs(ys - face).min() <= frame.resolution
    assert np.abs(ys - 2.0).min() > 1.5  # nothing occupied in the room
    assert set(np.unique(grid.cells)) <= {FREE, OCCUPIED, UNKNOWN}
    free_area = (grid.cells == FREE).sum() * 0.05**2
    assert free_area == pytest.approx(16.0, rel=0.06)


def test_rasterise_refuses_a_map_too_large() -> None:
    plan = build_floorplan("Huge", 1.0, [ObstacleShape("w", "IfcWall", box(0, 0, 600, 10.0))], spaces=[])
    frame = GridFrame(plan.outline.bounds, 0.005)
    assert frame.rows * frame.cols > MAX_GRID_PIXELS
    with pytest.raises(InputError, match="'Huge'.*coarser --resolution"):
        rasterise(plan, 0.005)
