"""The simulated world: ``SimWorld.raycast`` on the sample storeys against the brute force, the
grid-index cache, and workers giving way."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.records import FREE, Obstacle
from initcli.config import load_config
from initcli.config.building import choose_storey, prepare_site
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.sim.build import build_sim
from initcli.sim.driver import LidarSpec
from initcli.sim.scenario import WORKER_ROOM_M
from initcli.sim.world import SimWorld, Worker
from tests.helpers import SAMPLES

LIDAR = LidarSpec()


LIDAR_ANGLES = LIDAR.angle_min + LIDAR.angle_increment * np.arange(LIDAR.beams)


@pytest.fixture(scope="module", params=["ntu_hallway", "block_a", "block_b"])
def storey_world(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory):
    """(SimWorld, (n, 2) free cell centres) of a sample storey."""
    config = load_config(SAMPLES / f"{request.param}.site.yaml")
    site = prepare_site(config, tmp_path_factory.mktemp(request.param))
    storey, _ = choose_storey(config, site)
    setup = build_sim(config, site, storey, 3)
    grid = site.storeys[storey].grid
    rows, cols = np.nonzero(grid.cells == FREE)
    x, y = grid.cell_centre(rows, cols)
    return setup.world, np.column_stack([x, y]), setup.start


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


def test_worker_followed_gives_way_ahead_not_into_the_robot():
    """A worker walking away from a robot behind it that stops it gives way by walking on."""
    w = Worker(a=np.array([0.0, 0.0]), b=np.array([8.0, 0.0]), speed=1.0, phase=3.0)  # toward b
    robot = np.array([2.0, 0.0])  # 1 m behind it
    for _ in range(30):
        w.advance(0.1, robot)
    assert w.heading == 1 and w.position()[0] > 3.0 + 1.0


def test_worker_giving_way_steps_past_its_line_where_there_is_room():
    """At the end of its line a worker giving way walks on into the room beyond it (a person
    steps out of the narrow stretch), at most that far, then walks back to its line."""
    robot = np.array([6.0, 0.0])
    for room, reach in ((2.0, 10.0), (0.0, 8.0)):
        w = Worker(a=np.array([0.0, 0.0]), b=np.array([8.0, 0.0]), speed=1.0, phase=7.0, room_b=room)
        for _ in range(50):  # 1 m from the robot: waits 1 s, gives way, walks on toward b
            w.advance(0.1, robot)
        assert w.position()[0] == pytest.approx(reach)
    for _ in range(60):
        w.advance(0.1, np.array([-20.0, 0.0]))  # the robot gone: back along its line
    assert 0.0 <= w.position()[0] < 8.0


def test_workers_room_beyond_their_lines_is_free(storey_world) -> None:
    """The room place_workers gives a worker past each end of its line is free space it fits in,
    within WORKER_ROOM_M."""
    world, _, _ = storey_world
    static = SimWorld(world.static.copy())  # the walls and stacks, not the workers
    rooms = []
    for w in world.workers:
        u = (w.b - w.a) / w.length
        for end, step, room in ((w.a, -u, w.room_a), (w.b, u, w.room_b)):
            assert 0.0 <= room <= WORKER_ROOM_M
            for k in np.linspace(0.0, room, 7):
                x, y = end + k * step
                assert static.clearance(x, y, 0.0) > w.radius
            rooms.append(room)
    assert max(rooms) > 1.0  # corridors go on past some worker's line


def test_sample_storeys_match_brute_force(storey_world) -> None:
    world, free, start = storey_world
    rng = np.random.default_rng(7)
    origins = [np.array([start.x, start.y])] + list(free[rng.choice(len(free), 120)])
    for i, origin in enumerate(origins):
        t = 0.7 * i  # the workers move
        angles = LIDAR_ANGLES + rng.uniform(-math.pi, math.pi)
        segments = world.segments_at(float(origin[0]), float(origin[1]), LIDAR.max_range, t)
        expected = ray_segment_distances(origin, angles, segments, LIDAR.max_range)
        got = world.raycast(origin, angles, LIDAR.max_range, t)
        np.testing.assert_array_equal(got, expected)  # bit for bit, workers included


def test_segments_near_cache(storey_world) -> None:
    """The cached grid query returns what an uncached one does, the same segments each time."""
    world, free, _ = storey_world
    rng = np.random.default_rng(11)
    for x, y in free[rng.choice(len(free), 30)]:
        for radius in (1.0, 20.0):
            fresh = SimWorld(world.static.copy()).segments_near(x, y, radius)
            np.testing.assert_array_equal(world.segments_near(x, y, radius), fresh)
            np.testing.assert_array_equal(world.segments_near(x, y, radius), fresh)
    a, b = world.static[:, 0:2], world.static[:, 2:4]
    x, y = free[0]
    ab = b - a
    s = np.clip(
        np.einsum("ij,ij->i", [x, y] - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12), 0, 1
    )
    within = np.hypot(*(a + ab * s[:, None] - [x, y]).T) <= 20.0
    near = {tuple(r) for r in world.segments_near(x, y, 20.0)}
    assert {tuple(r) for r in world.static[within]} <= near


def _pane(x: float) -> Obstacle:
    """A 4 m glass pane along y at ``x`` (an open ring: the world closes it)."""
    return Obstacle(
        "", "pane", "IfcWindow", ((x, -2.0), (x + 0.02, -2.0), (x + 0.02, 2.0), (x, 2.0)), glass=True
    )


def test_glass_blocks_motion_but_lets_the_lidar_through_except_head_on() -> None:
    wall = Obstacle("", "wall", "IfcWall", ((6.0, -5.0), (6.2, -5.0), (6.2, 5.0), (6.0, 5.0)))
    world = SimWorld.from_obstacles([_pane(3.0), wall])
    assert world.glass is not None and world.glass.sum() == 4  # the open ring was closed: 4 edges
    origin = np.array([0.0, 0.0])
    head_on, slanted = world.raycast(origin, np.radians([0.0, 25.0]), 20.0, 0.0)
    assert head_on == pytest.approx(3.0, abs=1e-6)  # near-normal incidence: the pane reflects
    assert slanted == pytest.approx(6.0 / math.cos(math.radians(25.0)), abs=1e-6)  # through to the wall
    assert world.clearance(2.9, 0.5, 0.0, 1.0) == pytest.approx(0.1, abs=1e-6)  # but it is an obstacle


def test_open_obstacle_rings_are_closed() -> None:
    box = Obstacle("", "leaf", "DoorLeaf", ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)))
    world = SimWorld.from_obstacles([box])
    assert len(world.static) == 4
    # the closing edge (0, 1) -> (0, 0) is there: a ray from the left hits x = 0
    assert world.raycast(np.array([-1.0, 0.5]), np.array([0.0]), 5.0, 0.0)[0] == pytest.approx(1.0)


def _segment_distance(p: np.ndarray, seg: np.ndarray) -> float:
    """Distance from ``p`` to one segment, written out on its own."""
    a, b = seg[0:2], seg[2:4]
    ab = b - a
    s = 0.0 if float(ab @ ab) == 0.0 else min(max(float((p - a) @ ab) / float(ab @ ab), 0.0), 1.0)
    return float(np.hypot(*(a + s * ab - p)))


def test_clearance_is_the_distance_to_the_nearest_wall_or_worker() -> None:
    """The clearance (the collision check) against the plain definition: the nearest of the walls
    near the point and the workers' outlines at that time, capped at the radius."""
    rng = np.random.default_rng(3)
    walls = [
        Obstacle("", f"w{i}", "IfcWall", tuple(map(tuple, c + rng.uniform(-0.3, 0.3, (4, 2)))))
        for i, c in enumerate(rng.uniform(-6.0, 6.0, (25, 1, 2)))
    ]
    world = SimWorld.from_obstacles(walls)
    world.workers.append(Worker(np.array([-2.0, 0.0]), np.array([2.0, 0.0]), phase=1.3))
    for x, y in rng.uniform(-6.0, 6.0, (200, 2)):
        p = np.array([x, y])
        segments = world.segments_at(x, y, 1.5, 0.0)
        expected = min([1.5, *(_segment_distance(p, s) for s in segments)])
        assert world.clearance(x, y, 0.0, 1.5) == pytest.approx(expected, abs=1e-12)
