"""initcli.core.lidar.scan_landmarks: corners and openings in simulated scans (ray cast against known
walls, 2 cm range noise, 1 % dropped beams), against what bim-extract's rules find in the same walls."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import Point, box

from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.scan_landmarks import ScanLandmarkParams, scan_landmarks
from tests.landmark_worlds import RANGE_MAX, SETTINGS, corridor_with_door, l_room, room_with

PARAMS = ScanLandmarkParams.from_rules(SETTINGS)


def _seen(world, x, y, yaw=0.0, seed=0, **noise):
    """(landmarks, their positions in the world frame) of one noisy scan from (x, y, yaw)."""
    r, a0, inc = world.scan(x, y, yaw, np.random.default_rng(seed), **noise)
    found = scan_landmarks(r, a0, inc, RANGE_MAX, PARAMS)
    pose = Pose2D(x, y, yaw)
    return found, [pose.apply(f.xy[None])[0] for f in found]


def _nearest(truth, category, p):
    same = [t for t in truth if t.category == category]
    return min(same, key=lambda t: math.hypot(t.x - p[0], t.y - p[1])) if same else None


def test_params_take_the_rules_of_the_categories_file() -> None:
    assert PARAMS.corner_angle == pytest.approx((math.radians(60), math.radians(120)))
    assert (PARAMS.min_leg, PARAMS.opening_width, PARAMS.min_recess) == (0.3, (0.7, 2.5), 0.05)


@pytest.mark.parametrize("pose", [(2.0, 2.0, 0.0), (6.0, 2.0, 1.0), (2.0, 6.0, -2.0), (3.0, 3.0, 0.5)])
def test_l_room_corners_within_5_cm_with_the_right_kind_and_normal(pose) -> None:
    world = l_room()
    truth = world.truth()
    found, where = _seen(world, *pose, seed=int(pose[0] * 10 + pose[1]))
    assert len(found) >= 3
    for f, p in zip(found, where, strict=True):
        t = _nearest(truth, f.category, p)
        assert t is not None and math.hypot(t.x - p[0], t.y - p[1]) < 0.05, (f, p)
        heading = math.atan2(f.normal[1], f.normal[0]) + pose[2]
        assert abs(
            math.remainder(heading - math.atan2(t.normal[1], t.normal[0]), 2 * math.pi)
        ) < math.radians(10)
        assert f.width >= SETTINGS.min_leg
        sigma = math.sqrt(np.linalg.eigvalsh(f.cov).max())
        assert 0.0005 < sigma < 0.03  # centimetres, from the line fits


def test_the_convex_corner_of_the_l_is_seen_as_convex() -> None:
    found, where = _seen(l_room(), 2.0, 2.0)
    convex = [p for f, p in zip(found, where, strict=True) if f.category == "ConvexCorner"]
    assert len(convex) == 1 and np.hypot(*(convex[0] - [4.0, 4.0])) < 0.05


@pytest.mark.parametrize(
    ("recess", "from_y", "expected"), [(None, 1.0, True), (0.08, 1.0, True), (0.02, 1.0, False)]
)
def test_a_door_gap_in_the_corridor_wall_is_an_opening(recess, from_y, expected) -> None:
    world = corridor_with_door(recess)
    hits = []
    for seed, x in enumerate((5.0, 6.0, 7.0)):
        found, where = _seen(world, x, from_y, 0.3, seed=seed)
        hits += [(f, p) for f, p in zip(found, where, strict=True) if f.category == "Opening"]
    if not expected:
        assert hits == []
        return
    assert len(hits) >= 2
    for f, p in hits:
        assert np.hypot(*(p - [6.0, 2.0])) < 0.06
        assert f.width == pytest.approx(0.9, abs=0.1)
        assert f.normal[1] < -0.99 or abs(math.atan2(f.normal[1], f.normal[0]) + 0.3 + math.pi / 2) < 0.1


def test_no_opening_where_the_wall_has_no_gap_or_one_too_wide() -> None:
    for world in (corridor_with_door(gap=3.0), room_with(size=(12.0, 2.0))):
        for seed, x in enumerate((3.0, 6.0, 9.0)):
            found, _ = _seen(world, x, 1.0, seed=seed)
            assert [f for f in found if f.category == "Opening"] == []


def test_a_column_gives_column_corners() -> None:
    """A 0.4 m column seen from eight places 1.5-2 m round it: each of its corners comes as a column
    corner, from the side that sees both its faces, within 5 cm (a dropped beam at a face's end
    can cost one view its corner: faces this short are near min_leg)."""
    world = room_with(box(3.8, 2.8, 4.2, 3.2))
    truth = [t for t in world.truth() if t.category == "ColumnCorner"]
    corners = []
    for seed, (dx, dy) in enumerate(((-1.5, -1.5), (1.5, -1.5), (1.5, 1.5), (-1.5, 1.5)) * 2):
        found, where = _seen(world, 4.0 + dx, 3.0 + dy, seed=seed)
        corners += [p for f, p in zip(found, where, strict=True) if f.category == "ColumnCorner"]
    assert len(corners) >= 6
    nearest = [min(truth, key=lambda t: math.hypot(t.x - p[0], t.y - p[1])) for p in corners]
    assert {(t.x, t.y) for t in nearest} == {(t.x, t.y) for t in truth}
    for p, t in zip(corners, nearest, strict=True):
        assert math.hypot(t.x - p[0], t.y - p[1]) < 0.05


def test_clutter_makes_no_corner() -> None:
    """A 0.25 m box on the floor, seen from 1-4 m all round: no landmark near it (faces < min_leg)."""
    world = room_with(box(5.0, 2.0, 5.25, 2.25))
    rng = np.random.default_rng(3)
    for seed in range(20):
        a, d = rng.uniform(-math.pi, math.pi), rng.uniform(1.0, 3.5)
        x, y = 5.125 + d * math.cos(a), 2.125 + d * math.sin(a)
        if not world.free(x, y):
            continue
        _, where = _seen(world, x, y, seed=seed)
        assert all(np.hypot(*(p - [5.125, 2.125])) > 0.4 for p in where)


WORLDS = {
    "l_room": l_room,
    "door": corridor_with_door,
    "recessed_leaf": lambda: corridor_with_door(0.08),
    "column": lambda: room_with(box(3.8, 2.8, 4.2, 3.2)),
    "pillar": lambda: room_with(box(3.0, 2.0, 4.5, 3.5)),
    "clutter": lambda: room_with(box(5.0, 2.0, 5.25, 2.25)),
}


@pytest.mark.parametrize("name", sorted(WORLDS))
def test_accuracy_and_false_positives_over_random_poses(name) -> None:
    """40 random poses (>= 0.3 m from walls), 2 cm noise, 1 % dropouts: landmarks within 8 m are
    within 15 cm of one of the BIM rules' landmarks of their category (else a false positive);
    mean error under 1.5 cm, max under 9 cm, false positives at most one in 20 scans."""
    world = WORLDS[name]()
    truth = world.truth()
    rng = np.random.default_rng(sum(map(ord, name)))
    errors, false, scans = [], 0, 0
    minx, miny, maxx, maxy = world.rooms.bounds
    while scans < 40:
        x, y = rng.uniform(minx, maxx), rng.uniform(miny, maxy)
        if not world.free(x, y) or world.solid.distance(Point(x, y)) < 0.3:
            continue
        scans += 1
        found, where = _seen(world, x, y, rng.uniform(-math.pi, math.pi), seed=scans)
        for f, p in zip(found, where, strict=True):
            if f.range > 8.0:
                continue
            t = _nearest(truth, f.category, p)
            d = math.hypot(t.x - p[0], t.y - p[1]) if t is not None else math.inf
            if d < 0.15:
                errors.append(d)
            else:
                false += 1
    assert len(errors) > 2 * scans
    assert np.mean(errors) < 0.015 and np.max(errors) < 0.09
    assert false <= scans / 20


def test_a_270_degree_lidar_works_too() -> None:
    world = l_room()
    r, a0, inc = world.scan(2.0, 2.0, 0.0, np.random.default_rng(1))
    keep = slice(45, 315)  # drop the 90 degrees behind
    found = scan_landmarks(r[keep], a0 + 45 * inc, inc, RANGE_MAX, PARAMS)
    assert found and all(abs(math.atan2(f.y, f.x)) < math.radians(136) for f in found)
