"""initcli.sim.camera: the simulated RGB-D detector on a tiny world (one door, one wall)."""

from __future__ import annotations

import numpy as np
import pytest

from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
from initcli.core.geometry.se2 import Pose2D
from initcli.detector.profile import DetectorProfile, RecallTable
from initcli.sim.camera import CameraNoise, SimulatedDetector
from initcli.sim.synthetic_log import SimFeature
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


# --- with a measured profile (sim.detector.profile) -------------------------------------------------

NEAR = SimFeature("near", "door", 4.0, 0.0, norm_x=-1.0)  # 3.8 m from the camera: ~340 px tall
FAR = SimFeature("far", "door", 6.0, 0.0, norm_x=-1.0)  # 5.8 m: ~223 px tall
FLAT = CameraNoise(miss_rate=0.5, false_positives_per_minute=0.0, confusion_rate=0.0, pixel_noise=0.0)


def _profile(false: float = 0.0, confusion: dict | None = None) -> DetectorProfile:
    """Recall 0.9 for boxes over 150 px of a 320x320 input (300 px of the 640x480 camera), 0.2 below."""
    return DetectorProfile(
        model="m.onnx",
        sha256="0" * 64,
        classes=("door", "lift"),
        input_width=320,
        input_height=320,
        data="d",
        split="val",
        images=100,
        conf=0.25,
        iou=0.5,
        recall={
            "door": RecallTable((0.0, 150.0, 320.0), (50, 50), (10, 45)),
            "all": RecallTable((0.0, 320.0), (1,), (1,)),
        },
        false_boxes={"door": false},
        confusion=confusion or {"door": {"door": 1}},
        true_scores=(0.4, 0.8),
        false_scores=(0.25, 0.35),
    )


def _profiled(feature: SimFeature, profile: DetectorProfile, seed: int = 0) -> SimulatedDetector:
    world = SimWorld(static=np.zeros((0, 4)))
    rng = np.random.default_rng(seed)
    return SimulatedDetector([feature], DEFAULT_CAMERA, DEFAULT_MOUNT, FLAT, 5.0, world, rng, profile)


def _found_share(det: SimulatedDetector, images: int = 1500) -> float:
    return sum(len(det.detect(Pose2D(0, 0, 0), float(t))) for t in range(images)) / images


def test_a_profile_reproduces_its_recall_by_box_height() -> None:
    near, far = _profiled(NEAR, _profile()), _profiled(FAR, _profile())
    heights = [
        (o.bbox[3] - o.bbox[1]) * near.scale
        for f in (NEAR, FAR)
        for o in _detector([f]).detect(Pose2D(0, 0, 0), 0)
    ]
    assert heights[0] > 150 > heights[1]  # px of the model's input: one in each bin
    assert _found_share(near) == pytest.approx(0.9, abs=0.03)  # not the flat miss_rate 0.5
    assert _found_share(far) == pytest.approx(0.2, abs=0.03)


def test_a_profile_gives_false_boxes_per_image_classes_and_scores() -> None:
    det = _profiled(SimFeature("x", "door", 20.0, 20.0), _profile(false=0.7), seed=2)  # never in view
    counts = [len(det.detect(Pose2D(0, 0, 0), float(t))) for t in range(1500)]
    assert np.mean(counts) == pytest.approx(0.7, abs=0.06)
    assert max(counts) >= 3  # Poisson: several in one image, where the flat rate gives at most one
    confused = _profiled(NEAR, _profile(confusion={"door": {"door": 1, "lift": 3}}), seed=3)
    found = [o for t in range(1500) for o in confused.detect(Pose2D(0, 0, 0), float(t))]
    assert sum(o.cls == "lift" for o in found) / len(found) == pytest.approx(0.75, abs=0.04)
    assert all(0.4 <= o.score <= 0.8 for o in found)
