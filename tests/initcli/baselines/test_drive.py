"""The wall-following explorer of the baselines: one turn on the spot, then wall following."""

from __future__ import annotations

import math

import numpy as np
import pytest

from initcli.core.geometry import Pose2D
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
