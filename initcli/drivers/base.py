"""The driver interface between the initialisation session and a robot (simulated or real)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import DetectedObject

__all__ = ["LaserScan", "RobotDriver", "SensorFrame"]


@dataclass(frozen=True)
class LaserScan:
    angle_min: float
    angle_increment: float
    range_max: float
    ranges: np.ndarray  # metres; inf or range_max where nothing was hit

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))


@dataclass(frozen=True)
class SensorFrame:
    """What the robot reports after one control period."""

    t: float
    odom: Pose2D
    scan: LaserScan | None = None
    detections: list[DetectedObject] | None = None  # None: no image this period
    truth: Pose2D | None = None  # simulation only: the true pose in the BIM frame


class RobotDriver(Protocol):
    camera: CameraIntrinsics
    mount: CameraMount
    control_rate: float  # Hz
    depth_window: int

    def start(self) -> SensorFrame:
        """Begin the session; the odom frame's origin is the current pose (§3.3.1)."""
        ...

    def step(self, v: float, w: float) -> SensorFrame:
        """Apply (v m/s, w rad/s) for one control period and report the sensors."""
        ...

    @property
    def distance(self) -> float:
        """Distance driven so far (m)."""
        ...
