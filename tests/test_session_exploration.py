"""The exploration fixes that keep sessions out of dead loops: odometry-drift windows, going round
a stack on the open side, workers giving way, shuttle detection."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.bug_navigation import BugNavigator, BugParams, around_side
from initcli.core.confinement import confined
from initcli.core.detection_filter import ConfirmedFeature, within_drift_window
from initcli.core.geometry import Pose2D
from initcli.core.wall_following import ScanView
from initcli.drivers.base import SensorFrame
from initcli.sim.world import SimWorld, Worker, box_edges


def feature(i: int, t: float) -> ConfirmedFeature:
    return ConfirmedFeature(i, "door", float(i), 0.0, 5, t - 1.0, t)


def test_drift_window_keeps_the_features_of_the_last_metres():
    odom_t = np.arange(0.0, 101.0)  # 1 m/s along x for 100 s
    odom_xy = np.column_stack([odom_t, np.zeros_like(odom_t)])
    features = [feature(i, t) for i, t in enumerate([5.0, 20.0, 55.0, 70.0, 90.0, 99.0])]
    recent = within_drift_window(features, odom_t, odom_xy, 50.0)
    assert [f.index for f in recent] == [2, 3, 4, 5]
    # never fewer than keep_at_least (the newest)
    assert [f.index for f in within_drift_window(features, odom_t, odom_xy, 5.0, 3)] == [3, 4, 5]
    # standing still: nothing is old
    still = np.zeros((101, 2))
    assert len(within_drift_window(features, odom_t, still, 1.0)) == 6


def scan_of(points: np.ndarray) -> ScanView:
    """A 360-beam scan from the origin (robot facing +x) against the given wall segments."""
    from initcli.sim.world import ray_segment_distances

    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    ranges = ray_segment_distances(np.zeros(2), angles, points, 20.0)
    return ScanView.of(angles, ranges, 20.0)


def corridor_with_stack(stack_on_left: bool) -> np.ndarray:
    walls = np.array([[-5.0, 0.9, 20.0, 0.9], [-5.0, -0.9, 20.0, -0.9]])
    y = 0.65 if stack_on_left else -0.65
    stack = box_edges(0.8, y, 0.6, 0.25)
    return np.vstack([walls, stack])


def test_bug_goes_round_a_stack_on_the_open_side():
    # target straight ahead, slightly to the side of the stack: the open side still wins
    assert around_side(scan_of(corridor_with_stack(stack_on_left=True)), d_yaw=0.05) == 1
    assert around_side(scan_of(corridor_with_stack(stack_on_left=False)), d_yaw=-0.05) == -1
    # nothing to choose between: the target's side
    open_room = np.array([[2.0, -5.0, 2.0, 5.0]])
    assert around_side(scan_of(open_room), d_yaw=0.3) == -1
    assert around_side(scan_of(open_room), d_yaw=-0.3) == 1


def test_bug_turns_back_when_the_wall_leads_away_from_the_target():
    nav = BugNavigator(np.array([10.0, 0.0]), BugParams())
    nav.mode, nav.side, nav.hit_distance, nav.give_up_at = "follow", 1, 10.0, 11.5
    scan = scan_of(np.array([[-5.0, 0.9, 20.0, 0.9], [-5.0, -0.9, 20.0, -0.9]]))
    nav.step(Pose2D(-2.0, 0.0, math.pi), scan)  # 12 m away: the wrong way round
    assert nav.side == -1 and nav.flipped and nav.mode == "follow"
    nav.step(Pose2D(-4.0, 0.0, math.pi), scan)  # the other side leads away too: head for it
    assert nav.mode == "go"


def test_worker_gives_way_after_standing_face_to_face():
    w = Worker(a=np.array([0.0, 0.0]), b=np.array([8.0, 0.0]), speed=1.0, phase=2.0)
    robot = np.array([3.0, 0.0])  # 1 m ahead of the worker walking toward it
    for _ in range(round(0.8 * w.patience / 0.1)):  # waits
        w.advance(0.1, robot)
    assert np.allclose(w.position(), [2.0, 0.0])
    for _ in range(15):  # past its patience: turns round and walks away
        w.advance(0.1, robot)
    assert w.position()[0] < 2.0 - 0.3
    world = SimWorld.from_obstacles([], workers=[w])
    assert len(world.worker_segments(0.0)) == 4


def test_shuttling_is_told_from_travelling():
    trace: list[tuple[float, float, float]] = []
    hits = [
        confined(trace, t, Pose2D(5.0 * math.sin(t / 8.0), 0.0, 0.0), 150.0, 45.0, 8.0) for t in range(200)
    ]
    assert any(hits[140:])  # back and forth over 10 m for minutes
    trace.clear()
    hits = [confined(trace, t, Pose2D(0.5 * t, 0.0, 0.0), 150.0, 45.0, 8.0) for t in range(200)]
    assert not any(hits)  # a long straight drive


def test_scan_fit_tells_the_right_side_of_a_wall_from_the_wrong_one():
    from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
    from initcli.core.particle_filter import LikelihoodField, scan_fit
    from initcli.sim.world import ray_segment_distances

    # a 2 m corridor (y 0-2) beside a 10 m room (y 2-12), walls 1 cell thick, 0.05 m cells
    res = 0.05
    cells = np.full((260, 400), FREE, dtype=np.uint8)
    for y in (0.0, 2.0, 12.0):
        row = 259 - int(round(y / res)) - 10
        cells[row, :] = OCCUPIED
    cells[:, 0] = cells[:, 399] = OCCUPIED
    grid = OccupancyGrid(cells, res, (0.0, -0.5, 0.0))
    field = LikelihoodField(grid)
    walls = np.array(
        [[0, 0, 20, 0], [0, 2, 20, 2], [0, 12, 20, 12], [0, 0, 0, 12], [19.95, 0, 19.95, 12]], float
    )
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    truth = Pose2D(10.0, 1.0, 0.0)
    ranges = ray_segment_distances(truth.xy, angles, walls, 20.0)
    assert scan_fit(truth, angles, ranges, 20.0, field) > 0.9
    wrong = Pose2D(10.0, 3.0, 0.0)  # the room side of the same wall
    assert scan_fit(wrong, angles, ranges, 20.0, field) < 0.6


def test_explorer_turns_once_on_the_spot_before_following_walls():
    from initcli.baselines.drive import WallFollowingExplorer
    from initcli.config import SessionConfig
    from initcli.drivers.base import LaserScan

    config = SessionConfig()
    explorer = WallFollowingExplorer(config)
    scan = LaserScan(-math.pi, 2 * math.pi / 360, 20.0, np.full(360, 3.0))
    yaw, t, commands = 0.0, 0.0, []
    while t < 30.0:
        v, w = explorer.command(SensorFrame(t, Pose2D(0.0, 0.0, yaw), scan))
        commands.append((v, w))
        yaw = float(yaw + w * 0.1)
        t += 0.1
        if v > 0:
            break
    turned = sum(abs(w) * 0.1 for v, w in commands if v == 0)
    assert turned == pytest.approx(2 * math.pi, abs=0.1) and commands[-1][0] > 0
    config.exploration.initial_look = False
    assert WallFollowingExplorer(config).command(SensorFrame(0.0, Pose2D(0, 0, 0), scan))[0] > 0
