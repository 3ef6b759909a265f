"""initcli.sim.camera: the simulated RGB-D detector on a tiny world (one door, one wall)."""

from __future__ import annotations

import numpy as np
import pytest

from initcli.core.geometry import Pose2D
from initcli.sim.camera import CameraNoise, SimulatedDetector
from initcli.sim.synthetic_log import DEFAULT_CAMERA, DEFAULT_MOUNT, SimFeature
from initcli.sim.world import SimWorld

EXACT = CameraNoise(
    miss_rate=0.0, false_positives_per_minute=0.0, confusion_rate=0.0, depth_noise_quad=0.0, pixel_noise=0.0
)
DOOR = SimFeature("d1", "door", 4.0, 0.0, norm_x=-1.0, norm_y=0.0)  # faces the robot at the origin
LIFT = SimFeature("l1", "lift", 4.0, 3.0, norm_x=-1.0, norm_y=0.0)


def _detector(
    features: list[SimFeature], noise: CameraNoise = EXACT, walls: list | None = None, seed: int = 0
) -> SimulatedDetector:
    world = SimWorld(static=np.array(walls or [], dtype=float).reshape(-1, 4))
    return SimulatedDetector(
        features, DEFAULT_CAMERA, DEFAULT_MOUNT, noise, 5.0, world, np.random.default_rng(seed)
    )


def test_door_in_view_is_reported_with_its_depth_and_a_centred_box() -> None:
    found = _detector([DOOR]).detect(Pose2D(0, 0, 0), 0.0)
    assert len(found) == 1
    obj = found[0]
    assert obj.cls == "door"
    assert obj.depth == pytest.approx(4.0 - DEFAULT_MOUNT.x)
    u = 0.5 * (obj.bbox[0] + obj.bbox[2])
    assert u == pytest.approx(DEFAULT_CAMERA.cx, abs=1.0)
    assert 0.3 <= obj.score <= 0.99


def test_door_behind_the_robot_out_of_range_or_behind_a_wall_is_not_reported() -> None:
    det = _detector([DOOR])
    assert det.detect(Pose2D(0, 0, np.pi), 0.0) == []  # facing away
    assert det.detect(Pose2D(-5, 0, 0), 0.0) == []  # 9 m away, range 6 m
    walled = _detector([DOOR], walls=[[2.0, -1.0, 2.0, 1.0]])
    assert walled.detect(Pose2D(0, 0, 0), 0.0) == []


def test_door_seen_from_its_back_is_not_reported() -> None:
    back = SimFeature("d2", "door", 4.0, 0.0, norm_x=1.0, norm_y=0.0)
    assert _detector([back]).detect(Pose2D(0, 0, 0), 0.0) == []


def test_classes_exclude_phantoms_and_default_to_door() -> None:
    phantom = SimFeature("phantom_1", "poster", 4.0, 0.0, norm_x=-1.0)
    assert _detector([DOOR, LIFT, phantom]).classes == ["door", "lift"]
    assert _detector([]).classes == ["door"]


def test_confusion_swaps_the_class_for_another_known_class() -> None:
    noise = CameraNoise(
        miss_rate=0.0,
        false_positives_per_minute=0.0,
        confusion_rate=1.0,
        depth_noise_quad=0.0,
        pixel_noise=0.0,
    )
    far_lift = SimFeature("l1", "lift", 20.0, 20.0)  # known class, never in view
    found = _detector([DOOR, far_lift], noise).detect(Pose2D(0, 0, 0), 0.0)
    assert [o.cls for o in found] == ["lift"]


def test_miss_rate_one_reports_nothing() -> None:
    noise = CameraNoise(miss_rate=1.0, false_positives_per_minute=0.0, confusion_rate=0.0)
    det = _detector([DOOR], noise)
    assert all(det.detect(Pose2D(0, 0, 0), float(t)) == [] for t in range(20))


def test_false_positive_rate_follows_the_per_minute_setting() -> None:
    noise = CameraNoise(miss_rate=1.0, false_positives_per_minute=60.0 * 5.0 * 0.5, confusion_rate=0.0)
    det = _detector([], noise, seed=3)  # 0.5 false boxes per image at 5 Hz
    assert det.params.false_positive_rate == pytest.approx(0.5)
    n = sum(len(det.detect(Pose2D(0, 0, 0), float(t))) for t in range(400))
    assert 150 < n < 250
