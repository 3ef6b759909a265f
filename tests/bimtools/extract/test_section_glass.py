"""Glazing projected whole: a window whose cut meets only two jambs still closes its opening."""

from __future__ import annotations

import numpy as np
import pytest

from bimtools.extract.section import projected_footprint, section_polygon


def _box(x0, y0, z0, x1, y1, z1) -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[x, y, z] for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)], dtype=float)
    f = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    )  # fmt: skip
    return v, f


def _window() -> tuple[np.ndarray, np.ndarray]:
    """A 1.2 m window frame, 0.1 m deep, sill at 0.9 m, head at 2.1 m, no glass in the body."""
    parts = [
        _box(0.0, 0.0, 0.9, 0.05, 0.1, 2.1),  # left jamb
        _box(1.15, 0.0, 0.9, 1.2, 0.1, 2.1),  # right jamb
        _box(0.0, 0.0, 0.9, 1.2, 0.1, 0.95),  # sill
        _box(0.0, 0.0, 2.05, 1.2, 0.1, 2.1),  # head
    ]
    verts, faces, offset = [], [], 0
    for v, f in parts:
        verts.append(v)
        faces.append(f + offset)
        offset += len(v)
    return np.concatenate(verts), np.concatenate(faces)


def test_section_of_a_frame_meets_only_the_jambs():
    verts, faces = _window()
    cut = section_polygon(verts, faces, 1.0)
    assert cut is not None and cut.area == pytest.approx(2 * 0.05 * 0.1, rel=1e-3)


def test_projection_covers_the_whole_window():
    verts, _ = _window()
    area = projected_footprint(verts, -0.1, 2.5)
    assert area is not None
    assert area.area == pytest.approx(1.2 * 0.1, rel=1e-3)
    assert area.covers(area.centroid)
    minx, miny, maxx, maxy = area.bounds
    assert (minx, maxx) == pytest.approx((0.0, 1.2)) and (miny, maxy) == pytest.approx((0.0, 0.1))


def test_a_bare_glass_surface_gets_a_thin_footprint():
    verts = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 0.0, 3.0], [0.0, 0.0, 3.0]])
    area = projected_footprint(verts, -0.1, 2.5)
    assert area is not None and area.length == pytest.approx(4.04, abs=0.01)


def test_a_deep_element_is_not_projected():
    # A glazed element 2 m across in plan (a curved curtain wall as one body) is left to the section.
    verts, _ = _box(0.0, 0.0, 0.0, 3.0, 2.0, 3.0)
    assert projected_footprint(verts, -0.1, 2.5) is None
