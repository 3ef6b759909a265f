"""Sectioning meshes at a height."""

from __future__ import annotations

import numpy as np
import pytest

from bimtools.extract.section import section_polygon

BOX_FACES = np.array(
    [
        [0, 1, 2],
        [0, 2, 3],
        [4, 6, 5],
        [4, 7, 6],
        [0, 5, 1],
        [0, 4, 5],
        [1, 6, 2],
        [1, 5, 6],
        [2, 7, 3],
        [2, 6, 7],
        [3, 4, 0],
        [3, 7, 4],
    ]
)


def box(x0, y0, x1, y1, z0=0.0, z1=3.0):
    verts = np.array(
        [
            [x0, y0, z0],
            [x1, y0, z0],
            [x1, y1, z0],
            [x0, y1, z0],
            [x0, y0, z1],
            [x1, y0, z1],
            [x1, y1, z1],
            [x0, y1, z1],
        ],
        dtype=float,
    )
    return verts, BOX_FACES.copy()


def test_box_section_is_its_footprint():
    verts, faces = box(1, 2, 5, 2.2)
    area = section_polygon(verts, faces, 1.0)
    assert area.area == pytest.approx(0.8, abs=1e-6)
    assert area.bounds == pytest.approx((1, 2, 5, 2.2), abs=1e-6)


def test_section_outside_the_height_range_is_none():
    verts, faces = box(0, 0, 1, 1, 0, 0.5)
    assert section_polygon(verts, faces, 1.0) is None


def test_hollow_section_keeps_its_hole():
    # A square ring made of an outer box and an inverted inner box (a shaft wall).
    outer_v, outer_f = box(0, 0, 4, 4)
    inner_v, inner_f = box(1, 1, 3, 3)
    verts = np.vstack([outer_v, inner_v])
    faces = np.vstack([outer_f, inner_f[:, ::-1] + 8])
    area = section_polygon(verts, faces, 1.5)
    assert area.area == pytest.approx(16 - 4, abs=1e-6)
    assert not area.contains(__import__("shapely").Point(2, 2))
