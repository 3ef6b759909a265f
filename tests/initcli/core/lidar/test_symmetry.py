"""Self-similar storeys (initcli.core.lidar.symmetry): a turn that maps walls and features onto themselves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from initcli.core.lidar.symmetry import self_similar_turn

CELL = 0.05


def wall(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """The centres of the map cells of an axis-aligned wall, x0..x1 by y0..y1 (m)."""
    xs = np.arange(x0 + CELL / 2, x1, CELL)
    ys = np.arange(y0 + CELL / 2, y1, CELL)
    gx, gy = np.meshgrid(xs, ys)
    return np.column_stack([gx.ravel(), gy.ravel()])


def turned(points: np.ndarray, angle: float, centre: tuple[float, float]) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    d = points - centre
    return np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]]) + centre


def duplex_walls() -> np.ndarray:
    """A 16 x 10 m outline split at x = 8, a stub wall in the west home and its twin, turned 180
    degrees about (8, 5), in the east home."""
    parts = [
        wall(0.0, 0.0, 16.0, 0.1),
        wall(0.0, 9.9, 16.0, 10.0),
        wall(0.0, 0.1, 0.1, 9.9),
        wall(15.9, 0.1, 16.0, 9.9),
        wall(7.95, 0.1, 8.05, 9.9),
        wall(3.0, 0.1, 3.1, 4.0),  # the stub...
        wall(12.9, 6.0, 13.0, 9.9),  # ... and its twin
    ]
    return np.vstack(parts)


DOORS = np.array([[3.05, 6.0], [12.95, 4.0]])
NORMALS = np.array([[1.0, 0.0], [-1.0, 0.0]])
KINDS = np.array(["Door", "Door"], dtype=object)


def test_a_duplex_is_the_same_turned_half_round():
    turn = self_similar_turn(duplex_walls(), DOORS, NORMALS, KINDS)
    assert turn is not None
    assert turn.degrees == pytest.approx(180.0)
    assert math.dist(turn.centre, (8.0, 5.0)) < 1e-6  # the doors' own centroid, exact
    x, y, yaw = turn.twin(2.0, 1.0, 0.3)
    assert (x, y) == pytest.approx((14.0, 9.0)) and yaw == pytest.approx(0.3 - math.pi)


def test_a_stub_on_one_side_only_tells_the_twins_apart():
    walls = np.vstack([duplex_walls(), wall(1.0, 0.1, 1.1, 0.5)])  # 0.4 m of wall, west home only
    assert self_similar_turn(walls, DOORS, NORMALS, KINDS) is None


@pytest.mark.parametrize(
    ("doors", "normals", "kinds"),
    [
        (np.array([[3.05, 6.0], [12.95, 3.7]]), NORMALS, KINDS),  # a door 0.3 m along its wall
        (DOORS, np.array([[1.0, 0.0], [1.0, 0.0]]), KINDS),  # a door seen from the other side
        (DOORS, NORMALS, np.array(["Door", "Lift"], dtype=object)),  # a lift where its twin has a door
        (DOORS[:1], NORMALS[:1], KINDS[:1]),  # a door in one home only
    ],
)
def test_features_not_alike_tell_the_twins_apart(doors, normals, kinds):
    assert self_similar_turn(duplex_walls(), doors, normals, kinds) is None


def test_walls_alone_alike_with_no_features():
    """No features (a lidar-only table): the walls decide."""
    empty = np.zeros((0, 2))
    assert self_similar_turn(duplex_walls(), empty, empty, np.array([], dtype=object)) is not None


def outline(width: float = 16.0, height: float = 10.0) -> list[np.ndarray]:
    return [
        wall(0.0, 0.0, width, 0.1),
        wall(0.0, height - 0.1, width, height),
        wall(0.0, 0.1, 0.1, height - 0.1),
        wall(width - 0.1, 0.1, width, height - 0.1),
    ]


NONE = (np.zeros((0, 2)), np.zeros((0, 2)), np.array([], dtype=object))


def test_a_square_with_stubs_four_or_two_fold_is_the_same_turned_half_round():
    stub = wall(2.0, 0.1, 2.1, 3.0)
    stubs = [np.round(turned(stub, k * math.pi / 2, (5.0, 5.0)), 6) for k in range(4)]
    square = outline(10.0, 10.0)
    for kept in ([0, 1, 2, 3], [0, 2], [1, 3]):
        turn = self_similar_turn(np.vstack([*square, *[stubs[k] for k in kept]]), *NONE)
        assert turn is not None and turn.degrees == pytest.approx(180.0)
    assert self_similar_turn(np.vstack([*square, stubs[0], stubs[1]]), *NONE) is None


def test_a_triangle_is_the_same_turned_a_third():
    centre = (5.0, 5.0)
    arm = wall(5.0, 5.5, 5.1, 9.0)  # a wall from near the centre outwards, and its two turns
    arms = [np.round(turned(arm, k * 2 * math.pi / 3, centre), 6) for k in range(3)]
    turn = self_similar_turn(np.vstack(arms), *NONE)
    assert turn is not None and turn.degrees == pytest.approx(120.0)
    assert self_similar_turn(np.vstack(arms[:2]), *NONE) is None


@settings(max_examples=25, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(0.5, 14.0), st.floats(0.5, 8.0), st.floats(0.3, 1.5)), min_size=1, max_size=4
    )
)
def test_stubs_with_their_twins_are_alike_a_stub_alone_is_not(stubs):
    """Stubs with their twins turned about the outline's centre keep the storey self-similar; with one
    stub more, away from every twin, it is not."""
    pieces = [wall(x, y, x + 0.1, y + length) for x, y, length in stubs]
    twins = [np.round(turned(p, math.pi, (8.0, 5.0)), 6) for p in pieces]
    both = np.vstack([*outline(), *pieces, *twins])
    assert self_similar_turn(both, *NONE) is not None
    x, y, length = stubs[0]
    lone = wall(x + 0.5, y, x + 0.6, y + length)  # beside the first stub, 0.5 m east
    walls = np.vstack([both, lone])
    off, _ = cKDTree(walls).query(turned(lone, math.pi, (8.0, 5.0)))
    if off.max() > 0.2:  # some of its turned cells land off every wall (not on another stub)
        assert self_similar_turn(walls, *NONE) is None
