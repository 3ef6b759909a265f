"""The embedded robot: a simulator built from the BIM, behind the :class:`RobotDriver` interface.

Differential drive at 10 Hz in the storey's walls, drifting wheel odometry, a 2D lidar ray-cast
against walls, clutter and workers, and a camera + detector reporting detections at its rate.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.raycast import TWO_PI
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import LaserScan, SensorFrame
from initcli.io.detection_log import DetectedObject
from initcli.sim.robot import DiffDriveRobot
from initcli.sim.world import SimWorld

__all__ = ["CONTROL_RATE", "Detector", "LidarSpec", "SimDriver"]

CONTROL_RATE = 10.0  # Hz


@dataclass(frozen=True)
class LidarSpec:
    beams: int = 360
    fov: float = 2 * math.pi
    max_range: float = 20.0
    noise: float = 0.02
    dropout: float = 0.01

    @property
    def angle_min(self) -> float:
        return -self.fov / 2

    @property
    def angle_increment(self) -> float:
        full = abs(self.fov - 2 * math.pi) < 1e-9
        return self.fov / (self.beams if full else max(self.beams - 1, 1))


Detector = Callable[[Pose2D, float], list[DetectedObject]]


class SimDriver:
    """Commands in; odometry, scans and detections out (see :class:`initcli.drivers.base.RobotDriver`)."""

    control_rate = CONTROL_RATE

    def __init__(
        self,
        world: SimWorld,
        robot: DiffDriveRobot,
        lidar: LidarSpec,
        camera: CameraIntrinsics,
        mount: CameraMount,
        detector: Detector,
        detector_rate: float,
        max_linear: float,
        max_angular: float,
        rng: np.random.Generator,
        depth_window: int = 2,
    ):
        self.world = world
        self.robot = robot
        self.lidar = lidar
        self.camera = camera
        self.mount = mount
        self.detector = detector
        self.image_every = max(1, round(CONTROL_RATE / detector_rate))
        self.max_linear = max_linear
        self.max_angular = max_angular
        self.rng = rng
        self.depth_window = depth_window
        self.t = 0.0
        self.steps = 0
        self._angles = lidar.angle_min + lidar.angle_increment * np.arange(lidar.beams)
        self._full_turn = abs(lidar.fov - TWO_PI) < 1e-9 and lidar.beams >= 2

    @property
    def distance(self) -> float:
        return self.robot.distance

    def scan(self) -> LaserScan:
        p = self.robot.pose
        angles = self._angles + p.yaw
        # A full turn of evenly spaced beams: cast_rays need not check it at every scan.
        even = (float(angles[0]), TWO_PI / len(angles)) if self._full_turn else None
        ranges = self.world.raycast(np.array([p.x, p.y]), angles, self.lidar.max_range, self.t, even)
        max_range = self.lidar.max_range
        missed = ranges >= max_range
        noisy = ranges + self.rng.normal(0.0, self.lidar.noise, len(ranges))
        np.clip(noisy, 0.05, max_range - 1e-3, out=noisy)
        noisy[missed] = max_range  # no return: no noise either
        if self.lidar.dropout > 0:
            noisy[self.rng.random(len(noisy)) < self.lidar.dropout] = max_range
        return LaserScan(self.lidar.angle_min, self.lidar.angle_increment, self.lidar.max_range, noisy)

    def _frame(self) -> SensorFrame:
        detections = None
        if self.steps % self.image_every == 0:
            detections = self.detector(self.robot.pose, self.t)
        return SensorFrame(self.t, self.robot.odom, self.scan(), detections, self.robot.pose)

    def start(self) -> SensorFrame:
        return self._frame()

    def step(self, v: float, w: float) -> SensorFrame:
        v = min(max(float(v), -self.max_linear), self.max_linear)
        w = min(max(float(w), -self.max_angular), self.max_angular)
        dt = 1.0 / CONTROL_RATE
        target = self.robot.proposed(v, w, dt)
        if abs(v) > 1e-9 and self.world.clearance(target.x, target.y, self.t, 1.0) < self.robot.radius:
            # Bumped: only the rotation happens.
            target = Pose2D(self.robot.pose.x, self.robot.pose.y, target.yaw)
            self.robot.collisions += 1
        self.robot.move_to(target)
        self.world.advance(dt, np.array([target.x, target.y]))
        self.t += dt
        self.steps += 1
        return self._frame()
