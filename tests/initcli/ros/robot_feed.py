"""A robot that keeps moving, served over the loopback rosbridge test server: odometry on the
robot's clock (``header.stamp`` about 1.7e9 s, ROS 2 ``sec``/``nanosec`` or ROS 1
``secs``/``nsecs``) at 50 Hz, its simulated time running ``speed`` times faster than real time.
Its true pose in the map is :meth:`truth` (``MAP_FROM_ODOM`` * its odometry: noise-free wheels).
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

from initcli.core.geometry.se2 import Pose2D
from initcli.ros.nav2 import pose_dict, stamp_dict
from tests.initcli.ros.rosbridge_server import RosbridgeServer

T0 = 1_700_000_000.0  # s: the robot's clock at the feed's start
RATE = 50.0  # Hz
MAP_FROM_ODOM = Pose2D(12.0, -3.5, math.radians(70.0))  # where the robot's odom frame lies in the map


def odom_pose(t: float) -> Pose2D:
    """The robot's odometry ``t`` s after the feed's start: 0.5 m/s, turning at 0.2 rad/s."""
    yaw = 0.2 * t
    return Pose2D(2.5 * math.sin(yaw), 2.5 * (1 - math.cos(yaw)), yaw)


class MovingRobot:
    def __init__(self, server: RosbridgeServer, ros1: bool = False, speed: float = 1.0, topic: str = "/odom"):
        self.server, self.ros1, self.speed, self.topic = server, ros1, speed, topic
        self.sent: list[float] = []  # stamps of the odometry sent
        self._stop = threading.Event()
        self._odometry = threading.Event()
        self._odometry.set()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> MovingRobot:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=2)

    def stop_odometry(self) -> None:
        self._odometry.clear()

    def truth(self, stamp: float) -> Pose2D:
        return MAP_FROM_ODOM * odom_pose(stamp - T0)

    def message(self, stamp: float) -> dict[str, Any]:
        p = odom_pose(stamp - T0)
        return {
            "header": {"stamp": stamp_dict(stamp, self.ros1), "frame_id": "odom"},
            "child_frame_id": "base_link",
            "pose": {"pose": pose_dict(p.x, p.y, p.yaw), "covariance": [0.0] * 36},
        }

    def _run(self) -> None:
        start = time.monotonic()
        k = 0
        while not self._stop.is_set():
            stamp = T0 + k / RATE
            time.sleep(max(0.0, start + k / RATE / self.speed - time.monotonic()))
            if self._odometry.is_set():
                self.server.send(self.topic, self.message(stamp))
                self.sent.append(stamp)
            k += 1
