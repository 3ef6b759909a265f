"""The simulated ArUco markers of §4.3: placement, detection and the one-tag pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.load import StoreyModel
from initcli.config import load_config
from initcli.config.building import choose_storey, prepare_site
from initcli.core.features.marker_pose import robot_pose_from_marker
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.core.geometry.se2 import Pose2D
from initcli.sim.markers import (
    MAX_SHIFT,
    Marker,
    MarkerDetector,
    MarkerParams,
    detect_markers,
    place_markers,
)
from initcli.sim.world import SimWorld
from initcli.storey.circulation import Circulation
from tests.helpers import SAMPLES

CAMERA = CameraIntrinsics(320.0, 320.0, 320.0, 240.0, 640, 480)


MOUNT = CameraMount(0.2, 0.0, 1.0)


# A tag on a wall along the y axis, facing +x, at camera height.
TAG = Marker(0, 0.0, 0.0, 1.0, (1.0, 0.0), 0.0)


NOISELESS = MarkerParams(noise_base_px=0.0, noise_quad_px=0.0)


@pytest.fixture(scope="module")
def storey(tmp_path_factory: pytest.TempPathFactory) -> StoreyModel:
    config = load_config(SAMPLES / "block_a.site.yaml")
    site = prepare_site(config, tmp_path_factory.mktemp("block_a"))
    name, _ = choose_storey(config, site)
    return site.storeys[name]


def facing(marker: Marker, distance: float, view_deg: float = 0.0) -> Pose2D:
    """The robot pose whose camera is ``distance`` from the tag, ``view_deg`` off its normal,
    looking at it."""
    a = marker.yaw + math.radians(view_deg)
    cam = np.array([marker.x, marker.y]) + distance * np.array([math.cos(a), math.sin(a)])
    yaw = a + math.pi
    return Pose2D(cam[0] - MOUNT.x * math.cos(yaw), cam[1] - MOUNT.x * math.sin(yaw), yaw)


def on_wall(marker: Marker, storey: StoreyModel):
    for w in storey.walls:
        a, b, p = np.array([w.x1, w.y1]), np.array([w.x2, w.y2]), np.array([marker.x, marker.y])
        s = float(np.dot(p - a, b - a)) / w.length**2
        if 0.0 < s < 1.0 and np.hypot(*(a + s * (b - a) - p)) < 1e-6 and np.allclose(w.normal, marker.normal):
            return w
    return None


def test_six_markers_two_per_section_on_corridor_walls(storey: StoreyModel) -> None:
    circulation = Circulation.of(storey)
    markers = place_markers(storey, circulation)
    assert [m.id for m in markers] == list(range(6))
    assert sorted(m.section for m in markers) == [0, 0, 1, 1, 2, 2]
    static = SimWorld.from_obstacles(storey.obstacles).static
    for m in markers:
        wall = on_wall(m, storey)
        assert wall is not None, f"marker {m.id} is not on a wall surface"
        n = np.array(m.normal)
        assert circulation.contains(*(np.array([m.x, m.y]) + 0.4 * n)), "the tag faces the corridor"
        front = np.array([m.x, m.y]) + 0.3 * n
        behind = ray_segment_distances(front, np.array([m.yaw + math.pi]), static, 1.0)
        assert behind[0] == pytest.approx(0.3, abs=0.02), "solid wall behind the tag, not a door opening"
        assert m.z == pytest.approx(1.0) and m.size == pytest.approx(0.2)
        assert m.yaw == pytest.approx(math.atan2(m.normal[1], m.normal[0]))
    centres = []
    for k in range(3):
        a, b = (m for m in markers if m.section == k)
        # one tag on each wall of the corridor, facing each other, across the middle of the section
        assert np.dot(a.normal, b.normal) == pytest.approx(-1.0)
        u = np.array([-a.normal[1], a.normal[0]])
        assert abs(float(np.dot([b.x - a.x, b.y - a.y], u))) <= 2 * MAX_SHIFT
        centres.append([(a.x + b.x) / 2, (a.y + b.y) / 2])
    c = np.array(centres)
    spread = min(np.hypot(*(c[i] - c[j])) for i in range(3) for j in range(i + 1, 3))
    assert spread > 10.0, "sections are spread over the storey"
    # block_a: the west corridor section spans x 0.1..24.0 between y = 10.1 and 11.9; its
    # first tag sits exactly at the middle
    assert (markers[0].x, markers[0].y) == pytest.approx((12.05, 11.9))
    assert place_markers(storey, circulation) == markers, "deterministic for a storey"
    assert len(place_markers(storey, circulation, count=4)) == 4


def test_noiseless_detection_round_trips_the_robot_pose() -> None:
    for distance, view in [(1.0, 0.0), (2.0, 30.0), (3.0, -45.0), (3.5, 50.0), (1.5, 20.0)]:
        truth = facing(TAG, distance, view)
        truth = Pose2D(truth.x, truth.y, truth.yaw + math.radians(10.0))  # tag off the image centre
        seen = detect_markers([TAG], truth, CAMERA, MOUNT, None, NOISELESS)
        assert set(seen) == {0}
        pose = robot_pose_from_marker(seen[0], TAG, CAMERA, MOUNT)
        assert pose.distance_to(truth) < 0.01
        assert math.degrees(pose.yaw_error(truth)) < 0.1


def test_round_trip_on_a_placed_marker(storey: StoreyModel) -> None:
    markers = place_markers(storey, Circulation.of(storey))
    world = SimWorld.from_obstacles(storey.obstacles)
    for m in markers:
        truth = facing(m, 1.0, 25.0)
        seen = detect_markers(markers, truth, CAMERA, MOUNT, world, NOISELESS)
        assert m.id in seen
        pose = robot_pose_from_marker(seen[m.id], m, CAMERA, MOUNT)
        assert pose.distance_to(truth) < 0.01 and math.degrees(pose.yaw_error(truth)) < 0.1


def test_hidden_far_edge_on_small_or_behind_the_camera_is_not_detected() -> None:
    params = MarkerParams()
    assert 0 in detect_markers([TAG], facing(TAG, 3.0), CAMERA, MOUNT, None, params)
    wall = SimWorld(static=np.array([[1.5, -1.0, 1.5, 1.0]]))  # a wall between camera and tag
    assert detect_markers([TAG], facing(TAG, 3.0), CAMERA, MOUNT, wall, params) == {}
    side = SimWorld(static=np.array([[1.5, 1.0, 1.5, 3.0]]))  # a wall beside the line of sight
    assert 0 in detect_markers([TAG], facing(TAG, 3.0), CAMERA, MOUNT, side, params)
    far = MarkerParams(range=8.0, min_side_px=0.0)
    assert 0 in detect_markers([TAG], facing(TAG, 7.5), CAMERA, MOUNT, None, far)
    assert detect_markers([TAG], facing(TAG, 8.5), CAMERA, MOUNT, None, far) == {}
    assert 0 in detect_markers([TAG], facing(TAG, 2.0, 55.0), CAMERA, MOUNT, None, params)
    assert detect_markers([TAG], facing(TAG, 2.0, 70.0), CAMERA, MOUNT, None, params) == {}  # edge-on
    assert detect_markers([TAG], facing(TAG, 7.0), CAMERA, MOUNT, None, params) == {}  # 9 px wide
    behind = facing(TAG, 3.0)
    behind = Pose2D(behind.x, behind.y, behind.yaw + math.pi)
    assert detect_markers([TAG], behind, CAMERA, MOUNT, None, params) == {}
    # a tag on the wall's back face is never seen from the front
    back = Marker(1, 0.0, 0.0, 1.0, (-1.0, 0.0), math.pi)
    assert detect_markers([back], facing(TAG, 3.0), CAMERA, MOUNT, None, params) == {}


def test_miss_rate() -> None:
    rng = np.random.default_rng(3)
    detector = MarkerDetector([TAG], CAMERA, MOUNT, None, MarkerParams(), rng, miss_rate=0.3)
    hits = sum(bool(detector.detect(facing(TAG, 2.0, 20.0))) for _ in range(1000))
    assert 620 < hits < 780
    never = MarkerDetector([TAG], CAMERA, MOUNT, None, MarkerParams(), rng, miss_rate=1.0)
    assert never.detect(facing(TAG, 2.0)) == {}


def test_corner_noise_grows_with_distance() -> None:
    rng = np.random.default_rng(0)
    params = MarkerParams(range=15.0, min_side_px=0.0)

    def errors(distance: float) -> np.ndarray:
        truth = facing(TAG, distance, 30.0)
        out = []
        for _ in range(200):
            seen = detect_markers([TAG], truth, CAMERA, MOUNT, None, params, rng)
            out.append(robot_pose_from_marker(seen[0], TAG, CAMERA, MOUNT).distance_to(truth))
        return np.array(out)

    near, mid, far = errors(2.0), errors(4.0), errors(10.0)
    assert np.median(near) < 0.05, "a few cm at 2 m"
    assert np.median(mid) < 0.3
    assert np.median(far) > 2.0, "metres at 10 m (§4.3: the far, small marker)"
    assert np.mean(far) > 20 * np.mean(near)
