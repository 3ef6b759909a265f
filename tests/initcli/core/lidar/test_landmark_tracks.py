"""initcli.core.lidar.landmark_tracks: scan landmarks along a path, in the odom frame,
merged and confirmed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.landmark_tracks import (
    ScanInput,
    TrackParams,
    accumulate_landmarks,
    merge_sightings,
    to_odom,
)
from initcli.core.lidar.scan_landmarks import ScanLandmark, ScanLandmarkParams
from tests.landmark_worlds import RANGE_MAX, SETTINGS, l_room

PARAMS = ScanLandmarkParams.from_rules(SETTINGS)
START = Pose2D(1.0, 1.0, 0.4)  # the odom frame: origin at the start pose


def _drive(world, waypoints, odom_noise=0.0, seed=0, step=0.2):
    """Scans every ``step`` metres along straight legs between waypoints (heading along the leg),
    with the odometry pose relative to the start (plus a random walk of odom_noise m per metre)."""
    rng = np.random.default_rng(seed)
    scans, t, drift = [], 0.0, np.zeros(2)
    for (x0, y0), (x1, y1) in zip(waypoints, waypoints[1:], strict=False):
        yaw = math.atan2(y1 - y0, x1 - x0)
        n = max(1, int(math.hypot(x1 - x0, y1 - y0) / step))
        for k in range(n):
            x, y = x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n
            drift = drift + rng.normal(0.0, odom_noise * math.sqrt(step), 2)
            odom = START.inverse().compose(Pose2D(x + drift[0], y + drift[1], yaw))
            r, a0, inc = world.scan(x, y, yaw, rng)
            scans.append(ScanInput(t, odom, r, a0, inc, RANGE_MAX))
            t += 0.5
    return scans


def test_a_drive_round_the_l_room_confirms_each_corner_once_within_2_cm() -> None:
    world = l_room()
    truth = world.truth()
    scans = _drive(world, [(1.0, 1.0), (7.0, 1.0), (7.0, 3.0), (2.0, 3.0), (2.0, 7.0), (1.0, 7.0)])
    found = accumulate_landmarks(scans, PARAMS)
    assert [f.index for f in found] == list(range(len(found)))
    assert sorted(f.t_confirmed for f in found) == [f.t_confirmed for f in found]
    in_bim = [(f, START.apply(f.xy[None])[0]) for f in found]
    matched = {}
    for f, p in in_bim:
        t = min(truth, key=lambda t: math.hypot(t.x - p[0], t.y - p[1]))
        assert t.category == f.category and math.hypot(t.x - p[0], t.y - p[1]) < 0.02, (f, p)
        assert (t.x, t.y) not in matched, "a corner confirmed twice"
        matched[(t.x, t.y)] = f
        heading = math.atan2(f.normal[1], f.normal[0]) + START.yaw
        assert abs(
            math.remainder(heading - math.atan2(t.normal[1], t.normal[0]), 2 * math.pi)
        ) < math.radians(5)
        assert f.sightings >= TrackParams().min_sightings
        assert 1e-4 < f.sigma < 0.01  # the mean of many centimetre sightings
    assert len(matched) == len(truth)  # all six corners of the L


def test_odometry_drift_of_a_centimetre_per_metre_still_merges() -> None:
    world = l_room()
    scans = _drive(world, [(1.0, 1.0), (7.0, 1.0), (7.0, 3.0)], odom_noise=0.01, seed=4)
    found = accumulate_landmarks(scans, PARAMS)
    kinds = sorted(f.category for f in found)
    assert kinds.count("ConvexCorner") == 1 and kinds.count("ConcaveCorner") >= 4
    assert len(found) <= 7  # one or two pass twice, no more


def test_to_odom_turns_position_normal_and_covariance() -> None:
    cov = np.diag([0.02**2, 0.01**2])
    seen = ScanLandmark("ConcaveCorner", 2.0, 0.0, (-1.0, 0.0), 1.0, cov)
    (s,) = to_odom(3.0, 7, Pose2D(1.0, 1.0, math.pi / 2), [seen], mount=Pose2D(0.5, 0.0, 0.0))
    assert (s.x, s.y) == pytest.approx((1.0, 3.5))
    assert s.normal == pytest.approx((0.0, -1.0), abs=1e-12)
    np.testing.assert_allclose(s.cov, np.diag([0.01**2, 0.02**2]), atol=1e-12)
    assert (s.t, s.frame, s.range) == (3.0, 7, 2.0)


def test_a_landmark_seen_fewer_than_k_times_is_not_confirmed_and_far_ones_are_dropped() -> None:
    cov = np.eye(2) * 1e-4
    near = [ScanLandmark("ConvexCorner", 1.0, 0.0, (1.0, 0.0), 1.0, cov)]
    far = [ScanLandmark("ConcaveCorner", 9.0, 0.0, (-1.0, 0.0), 1.0, cov)]
    sightings = []
    for frame in range(5):
        sightings += to_odom(float(frame), frame, Pose2D.identity(), far + (near if frame < 2 else []))
    assert merge_sightings(sightings, TrackParams()) == []  # near seen twice, far beyond max_range
    confirmed = merge_sightings(sightings, TrackParams(min_sightings=2, max_range=10.0))
    assert sorted(f.category for f in confirmed) == ["ConcaveCorner", "ConvexCorner"]
    far_one = next(f for f in confirmed if f.category == "ConcaveCorner")
    np.testing.assert_allclose(far_one.cov, cov / 5)  # the mean of five sightings


def test_confirmed_landmarks_go_into_the_detection_log_as_lidar_features(tmp_path) -> None:
    from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
    from initcli.io.detection_log import Meta, read_log
    from initcli.io.log_writer import landmark_records, write_log

    found = accumulate_landmarks(_drive(l_room(), [(1.0, 1.0), (7.0, 1.0)]), PARAMS)
    assert found
    path = tmp_path / "log.jsonl"
    write_log(path, [Meta(DEFAULT_CAMERA, DEFAULT_MOUNT), *landmark_records(found)])
    back = read_log(path).features
    assert [(f.cls, f.source) for f in back] == [(f.category, "lidar") for f in found]
    assert [(f.x, f.y, f.t) for f in back] == [(f.x, f.y, f.t_confirmed) for f in found]
