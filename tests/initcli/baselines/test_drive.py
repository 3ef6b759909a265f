"""The wall-following explorer of the baselines: one turn on the spot, then wall following."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import SensorFrame


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


def test_one_shared_drive_gives_each_baseline_the_outcome_it_has_alone(tmp_path) -> None:
    """AMCL and the markers on one drive (as bim-init eval runs them) end exactly where and how
    each ends when it drives alone from the same simulated setup."""
    import dataclasses

    from initcli.baselines.amcl import AmclAttempt, run_amcl
    from initcli.baselines.drive import drive_attempts
    from initcli.baselines.markers import MarkerAttempt, run_markers
    from initcli.config import load_config
    from initcli.config.building import choose_storey, prepare_site
    from initcli.sim.build import build_sim
    from tests.helpers import SAMPLES

    config = load_config(SAMPLES / "block_a.site.yaml", reality="construction")
    config = dataclasses.replace(config, limits=dataclasses.replace(config.limits, max_distance=25.0))
    site = prepare_site(config, tmp_path / "site")
    storey, _ = choose_storey(config, site)
    for seed in (3, 8):
        alone = [
            run_amcl(config, site, build_sim(config, site, storey, seed), np.random.default_rng(seed + 1)),
            run_markers(config, site, build_sim(config, site, storey, seed), np.random.default_rng(seed + 2)),
        ]
        setup = build_sim(config, site, storey, seed)
        shared = drive_attempts(
            config,
            setup.driver,
            [
                AmclAttempt(config, site, setup, np.random.default_rng(seed + 1)),
                MarkerAttempt(config, site, setup, np.random.default_rng(seed + 2)),
            ],
        )
        for a, b in zip(alone, shared, strict=True):
            assert dataclasses.replace(a, wall_seconds=0.0) == dataclasses.replace(b, wall_seconds=0.0)
        assert alone[0].distance_m != alone[1].distance_m  # they end at different places


@pytest.mark.parametrize(("across", "looks"), [(50.0, 2), (1.3, 0)])  # an open floor, a corridor
def test_explorer_looks_again_along_a_wall_with_open_space_beside_it(across: float, looks: int) -> None:
    """Like the session: every ``exploration.look_every`` m of travel along a wall with nothing
    within 3 m on the other side, one turn on the spot; in a corridor none."""
    from initcli.baselines.drive import WallFollowingExplorer
    from initcli.config import SessionConfig
    from initcli.drivers.base import LaserScan

    config = SessionConfig()
    config.exploration.initial_look = False
    config.exploration.cross_after = 0
    explorer = WallFollowingExplorer(config)
    angles = -math.pi + 2 * math.pi / 360 * np.arange(360)
    sin = np.sin(angles)
    with np.errstate(divide="ignore"):
        ranges = np.minimum(np.where(sin > 0, 0.7 / sin, np.where(sin < 0, across / -sin, np.inf)), 20.0)
    scan = LaserScan(-math.pi, 2 * math.pi / 360, 20.0, ranges)  # the left wall at 0.7 m, the same everywhere
    pose, turned = Pose2D(0.0, 0.0, 0.0), 0.0
    for step in range(700):  # 25 m at 0.5 m/s with the looks' turns
        v, w = explorer.command(SensorFrame(step * 0.1, pose, scan))
        turned += abs(w) * 0.1 if v == 0 else 0.0
        pose = pose * Pose2D(v * 0.1, 0.0, w * 0.1)
    assert pose.x > 20.0
    assert turned == pytest.approx(looks * 2 * math.pi, abs=0.2)


@pytest.mark.parametrize(("across", "crossing"), [(11.0, True), (1.3, False)])  # an open floor, a corridor
def test_explorer_crosses_the_open_floor_after_a_look_like_the_session(across: float, crossing: bool) -> None:
    """After a look along a wall with the floor open 11 m to the other side, the drive turns square
    across, as the session does (the scan is the same in the robot's frame everywhere, so it drives
    on that way); in a corridor it drives on along the wall."""
    from initcli.baselines.drive import WallFollowingExplorer
    from initcli.config import SessionConfig
    from initcli.drivers.base import LaserScan

    config = SessionConfig()
    config.exploration.initial_look = False
    config.exploration.cross_after = 1  # after the first look
    explorer = WallFollowingExplorer(config)
    angles = -math.pi + 2 * math.pi / 360 * np.arange(360)
    sin = np.sin(angles)
    with np.errstate(divide="ignore"):
        ranges = np.minimum(np.where(sin > 0, 0.7 / sin, np.where(sin < 0, across / -sin, np.inf)), 20.0)
    scan = LaserScan(-math.pi, 2 * math.pi / 360, 20.0, ranges)
    pose = Pose2D(0.0, 0.0, 0.0)
    for step in range(700):
        v, w = explorer.command(SensorFrame(step * 0.1, pose, scan))
        pose = pose * Pose2D(v * 0.1, 0.0, w * 0.1)
    if crossing:
        assert pose.x == pytest.approx(10.0, abs=0.7) and pose.y < -8.0
    else:
        assert abs(pose.y) < 0.5 and pose.x > 20.0
