"""Lift evidence: a lift space is a shaft only when shaft-sized; exterior doors enter nothing; a
stair foot faces open floor."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import box

from bimtools.extract.circulation import FreeRegions, SideProbe, SpaceIndex
from bimtools.extract.features import BodyCandidate, StoreyContext, is_shaft_space, storey_features
from bimtools.ifc.categories import load_categories
from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid


def _category(name: str):
    return next(c for c in load_categories().categories if c.name == name)


def test_a_big_space_named_elevator_is_no_shaft():
    lift = _category("Lift")
    assert lift.is_space("Elevator (N.I.C.)")
    assert is_shaft_space(lift, 5.0)
    assert not is_shaft_space(lift, 40.0)  # a lobby-sized "Elevator (N.I.C.)" placeholder
    assert is_shaft_space(_category("Stairs"), 40.0)  # staircases are not bounded by this rule


def test_outside_is_not_reachable():
    assert not SideProbe(label=0, space="", point=(0.0, 0.0)).reachable
    assert SideProbe(label=0, space="Lift", point=(0.0, 0.0), space_index=2, space_area=4.0).reachable
    assert SideProbe(label=5, space="", point=(0.0, 0.0)).reachable


def _stair_storey(wall: tuple[float, float] | None) -> tuple[StoreyContext, BodyCandidate]:
    """A 6 x 3 m floor (0.05 m cells), walled round, with a wall across it from x = ``wall[0]``
    to ``wall[1]`` (none: open), and a straight flight climbing +x from x = 1.0 at y 1-2 (its foot
    faces -x, towards that wall)."""
    res = 0.05
    cells = np.full((60, 120), FREE, dtype=np.uint8)
    if wall is not None:
        cells[:, round(wall[0] / res) : round(wall[1] / res)] = OCCUPIED
    cells[[0, -1], :] = OCCUPIED
    cells[:, [0, -1]] = OCCUPIED
    grid = OccupancyGrid(cells, res, (0.0, 0.0, 0.0))
    ctx = StoreyContext("Level 0", 0.0, FreeRegions(grid), SpaceIndex([], []), load_categories())
    steps = [[1.0 + 0.3 * k, y, 0.15 * k] for k in range(12) for y in (1.0, 2.0)]
    body = BodyCandidate(
        guid="stair-guid",
        ifc_class="IfcStair",
        name="Stair 1",
        category="Stairs",
        footprint=box(1.0, 1.0, 4.3, 2.0),
        points=np.array([[2.0, 1.5]]),
        parts=[np.array(steps)],
    )
    return ctx, body


def test_a_stair_foot_facing_open_floor_is_a_feature():
    ctx, body = _stair_storey(None)
    (feature,) = storey_features(ctx, [], [body])
    assert (feature.category, feature.x, feature.y) == ("Stairs", pytest.approx(1.0), pytest.approx(1.5))
    assert (feature.norm_x, feature.norm_y) == (pytest.approx(-1.0), pytest.approx(0.0))
    assert ctx.warnings == []


def test_a_stair_foot_facing_a_wall_is_skipped_with_a_warning():
    # a wall 0.2-0.5 m in front of the foot, free floor beyond it: the probe finds the room behind,
    # but the floor right in front of the foot is not free
    ctx, body = _stair_storey((0.5, 0.8))
    assert storey_features(ctx, [], [body]) == []
    assert ctx.warnings == ["storey 'Level 0': stair 'Stair 1' (stair-guid): its foot faces a wall, skipped"]


def test_a_stair_foot_outside_the_building_is_skipped_with_a_warning():
    ctx, body = _stair_storey((0.0, 0.8))  # nothing but wall and the map's edge in front of the foot
    assert storey_features(ctx, [], [body]) == []
    assert ctx.warnings == [
        "storey 'Level 0': stair 'Stair 1' (stair-guid): its foot is outside the building, skipped"
    ]
