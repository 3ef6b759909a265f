"""initcli.core.lidar.scan_lines: split-and-merge lines of one scan, their fits and
what lies past their ends."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import box

from initcli.core.lidar.scan_lines import (
    CONTINUES,
    FARTHER,
    NEARER,
    NOTHING,
    LineParams,
    extract_lines,
    scan_points,
)
from tests.landmark_worlds import RANGE_MAX, room_with


def _lines(world, x, y, yaw=0.0, seed=None, **noise):
    rng = np.random.default_rng(seed) if seed is not None else None
    r, a0, inc = world.scan(x, y, yaw, rng, **noise)
    return extract_lines(r, a0, inc, RANGE_MAX)


def test_a_room_seen_all_round_is_four_closed_lines() -> None:
    lines = _lines(room_with(), 3.0, 2.0)
    assert len(lines) == 4
    assert all(s.before == CONTINUES and s.after == CONTINUES for s in lines)
    # in the sensor frame the walls are x = -3, x = 5, y = -2, y = 4, normals towards the sensor
    offsets = sorted(round(float(s.normal @ s.centroid), 3) for s in lines)
    assert offsets == pytest.approx([-5.0, -4.0, -3.0, -2.0], abs=0.002)
    for s in lines:
        assert s.distance(np.zeros(2)) > 0


def test_noise_and_dropouts_do_not_cut_a_wall() -> None:
    """2 cm noise and 2 % dropped beams (a 1 % lidar twice over): still four walls, each fit to
    about a centimetre."""
    for seed in range(5):
        lines = _lines(room_with(), 3.0, 2.0, 0.3, seed=seed, dropout=0.02)
        assert len(lines) == 4, seed
        for s in lines:
            assert abs(abs(float(s.normal @ s.centroid)) - round(abs(float(s.normal @ s.centroid)))) < 0.02
            assert 0.01 < s.sigma < 0.03
            assert s.var_offset == pytest.approx(s.sigma**2 / s.points)


def test_line_covariance_matches_the_scatter_of_repeated_fits() -> None:
    """The stated offset and angle variances agree with the spread over repeated noisy scans."""
    world = room_with()
    offsets, angles, predicted = [], [], []
    for seed in range(60):
        lines = _lines(world, 3.0, 2.0, 0.0, seed=seed, dropout=0.0)
        east = max(lines, key=lambda s: s.centroid[0])  # the wall x = 5 (sensor frame)
        offsets.append(float(east.normal @ east.centroid))
        angles.append(math.atan2(east.direction[1], east.direction[0]))
        predicted.append((east.normal_variance_at(np.array([5.0, 0.0])), east.var_angle))
    var_angle = np.mean([p[1] for p in predicted])
    assert np.var(angles) == pytest.approx(var_angle, rel=0.6)
    assert np.std(offsets) < 0.01


def test_an_occluding_edge_is_farther_past_the_end() -> None:
    """A free-standing 1 m box in front of the far wall: its faces end in an edge with the wall
    behind (farther), the wall's pieces end where the box hides them (nearer)."""
    lines = _lines(room_with(box(3.5, 1.5, 4.5, 2.5)), 1.0, 2.0)
    (face,) = [s for s in lines if abs(s.centroid[0] - 2.5) < 0.05]  # x = 3.5 in the world
    assert face.points >= LineParams().min_points
    assert (face.before, face.after) == (FARTHER, FARTHER)
    hidden = [s for s in lines if abs(s.centroid[0] - 7.0) < 0.05]  # the east wall, behind the box
    assert {NEARER} <= {s.before for s in hidden} | {s.after for s in hidden}


def test_scan_points_marks_no_returns() -> None:
    valid, pts = scan_points(np.array([1.0, 20.0, np.nan, 0.01, 2.0]), 0.0, 0.5, 20.0)
    assert valid.tolist() == [True, False, False, False, True]
    assert np.isnan(pts[1]).all() and pts[0] == pytest.approx([1.0, 0.0])


def test_a_partial_scan_ends_in_nothing() -> None:
    world = room_with()
    r, a0, inc = world.scan(3.0, 2.0)
    half = slice(0, 180)  # the back half of the turn: a 180 degree lidar
    lines = extract_lines(r[half], a0, inc, RANGE_MAX, full_turn=False)
    assert lines[0].before == NOTHING and lines[-1].after == NOTHING
    assert len(extract_lines(np.full(10, RANGE_MAX), a0, inc, RANGE_MAX)) == 0
