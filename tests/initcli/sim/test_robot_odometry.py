"""Systematic odometry errors of the simulated robot: scale error and wheel slip (initcli.sim.robot)."""

from __future__ import annotations

import numpy as np

from initcli.core.geometry.se2 import Pose2D
from initcli.sim.robot import DiffDriveRobot, OdometryNoise

EXACT = OdometryNoise(0.0, 0.0, 0.0, 0.0)


def drive_straight(noise: OdometryNoise, metres: float, seed: int = 0) -> DiffDriveRobot:
    robot = DiffDriveRobot(Pose2D(0.0, 0.0, 0.0), 0.3, noise, np.random.default_rng(seed))
    for _ in range(int(metres / 0.05)):
        robot.move_to(robot.proposed(0.5, 0.0, 0.1))
    return robot


def test_scale_error_counts_too_far() -> None:
    robot = drive_straight(OdometryNoise(0.0, 0.0, 0.0, 0.0, scale_error=0.02), 10.0)
    assert abs(robot.pose.x - 10.0) < 1e-6
    assert abs(robot.odom.x - 10.2) < 1e-6
    assert robot.slips == 0


def test_slips_add_ground_the_robot_did_not_cover() -> None:
    robot = drive_straight(OdometryNoise(0.0, 0.0, 0.0, 0.0, slip_per_100m=20.0), 50.0)
    assert robot.slips >= 3  # 10 expected in 50 m
    assert robot.odom.distance_to(Pose2D(50.0, 0.0, 0.0)) > 0.05 * robot.slips * 0.5
    assert abs(robot.pose.x - 50.0) < 1e-6


def test_no_systematic_error_draws_nothing_extra() -> None:
    a = drive_straight(OdometryNoise(), 5.0, seed=3)
    b = drive_straight(OdometryNoise(slip_per_100m=0.0, scale_error=0.0), 5.0, seed=3)
    assert a.odom == b.odom
    assert drive_straight(EXACT, 5.0).odom.distance_to(Pose2D(5.0, 0.0, 0.0)) < 1e-9


def test_scaled_keeps_systematic_errors() -> None:
    n = OdometryNoise(scale_error=0.02, slip_per_100m=1.0).scaled(4.0)
    assert n.alpha3 == 4 * OdometryNoise().alpha3
    assert n.scale_error == 0.02 and n.slip_per_100m == 1.0
