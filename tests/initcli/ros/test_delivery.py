"""initcli.ros.delivery against a moving robot served over loopback rosbridge: the pose is carried
to the newest odometry and stamped on the robot's clock, advertised before it is published,
re-published until the AMCL stand-in confirms it, flushed before the link closes; ROS 1 and
ROS 2 stamps."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from initcli.config import Nav2Section
from initcli.core.filters.particle_filter import FilterNoise
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.ros.rosbridge_driver import header_stamp
from initcli.ros.tf import quaternion_yaw
from tests.initcli.ros.robot_feed import MovingRobot
from tests.initcli.ros.rosbridge_server import RosbridgeServer

pytest.importorskip("roslibpy")

from initcli.config import RosbridgeSection  # noqa: E402
from initcli.ros.delivery import CarriedPose, deliver_initial_pose  # noqa: E402
from initcli.ros.rosbridge import RosbridgeLink  # noqa: E402
from initcli.ros.rosbridge_driver import RosbridgeDriver  # noqa: E402

CAMERA = CameraIntrinsics(fx=320.0, fy=320.0, cx=320.0, cy=240.0, width=640, height=480)
COV = np.diag([0.004, 0.004, 0.0004])
CLAIM_ERROR = Pose2D(0.04, -0.03, math.radians(0.8))  # what fine tuning got wrong


def _settings(timeout: float = 3.0, republish: float = 0.3) -> Nav2Section:
    nav2 = Nav2Section(advertise_delay=0.05)
    nav2.confirm.timeout, nav2.confirm.republish_period = timeout, republish
    return nav2


def _pose_of(msg: dict) -> Pose2D:
    p, q = msg["pose"]["pose"]["position"], msg["pose"]["pose"]["orientation"]
    return Pose2D(p["x"], p["y"], quaternion_yaw(q["x"], q["y"], q["z"], q["w"]))


def _deliver(server: RosbridgeServer, robot: MovingRobot, settings: Nav2Section, drive_on: float = 0.6):
    """A session claimed (with CLAIM_ERROR) at the frame after the start; the robot drives on
    ``drive_on`` s before the pose goes out. Returns (report, claim stamp, newest odometry at send)."""
    with RosbridgeLink("127.0.0.1", server.port) as link:
        driver = RosbridgeDriver(link, CAMERA, CameraMount(), RosbridgeSection(), drive=False, period=0.02)
        driver.start()
        frame = driver.step(0.0, 0.0)
        claim_stamp = driver.frame_stamp
        claimed = robot.truth(claim_stamp) * CLAIM_ERROR
        carried = CarriedPose(
            claimed * frame.odom.inverse(), COV, claim_stamp, driver.odometry, FilterNoise()
        )
        time.sleep(drive_on)
        report = deliver_initial_pose(link, carried, settings, driver.ros1)
        newest = robot.sent[-1]
        assert driver.ros1 == robot.ros1
    return report, claim_stamp, newest


@pytest.mark.parametrize("ros1", [False, True], ids=["ros2-stamps", "ros1-secs-nsecs"])
def test_the_pose_is_carried_to_the_robots_clock_and_confirmed(ros1: bool) -> None:
    with RosbridgeServer(rosapi=True, amcl=True) as server, MovingRobot(server, ros1=ros1) as robot:
        assert server.wait_for(lambda: True, 0.1)
        report, claim_stamp, newest = _deliver(server, robot, _settings())
        sent = server.published("/initialpose")
    assert sent and report["confirmed"] is True and report["flushed"] is True
    assert report["advertised"] == "rosapi"
    msg = sent[0]
    stamp = msg["header"]["stamp"]
    assert set(stamp) == ({"secs", "nsecs"} if ros1 else {"sec", "nanosec"})
    t = header_stamp(msg)
    assert t > 1.6e9 and t - claim_stamp > 0.4  # the newest odometry, not the claim's
    assert abs(newest - t) < 0.5  # on the robot's clock, within 0.5 s of its newest odometry
    truth = robot.truth(t)
    ours = _pose_of(msg)
    assert ours.distance_to(truth) < 0.15 and math.degrees(ours.yaw_error(truth)) < 3.0
    assert ours.distance_to(robot.truth(claim_stamp)) > 0.2  # the robot had moved on since the claim
    cov = msg["pose"]["covariance"]
    assert cov[0] > COV[0, 0] and cov[35] > COV[2, 2]  # grown by the motion since the claim
    assert report["amcl_error_m"] < 0.3 and report["sends"] >= 1


def test_advertised_before_published_and_republished_until_amcl_takes_it() -> None:
    with RosbridgeServer(rosapi=False, amcl=True, amcl_ignores=2, set_initial_pose=True) as server:
        with MovingRobot(server, speed=2.0) as robot:
            report, _, _ = _deliver(server, robot, _settings(timeout=5.0, republish=0.3), drive_on=0.1)
        ops = [(o["op"], o.get("topic")) for o in server.ops if o.get("topic") == "/initialpose"]
    assert ops[0] == ("advertise", "/initialpose")
    assert report["advertised"] == "delay"  # no rosapi: waited nav2.advertise_delay
    assert report["confirmed"] is True and report["sends"] == 3  # two were ignored by AMCL
    stamps = report["sent_stamps"]
    assert stamps == sorted(stamps) and stamps[-1] > stamps[0]  # each send carried to the newest odometry
    assert report["set_initial_pose"] == {"called": True, "answer": {}}


def test_no_amcl_is_reported_unconfirmed_after_the_timeout() -> None:
    with RosbridgeServer(rosapi=True) as server, MovingRobot(server) as robot:
        start = time.monotonic()
        report, _, _ = _deliver(server, robot, _settings(timeout=0.8, republish=0.3), drive_on=0.1)
        took = time.monotonic() - start
        assert server.wait_for(lambda: len(server.published("/initialpose")) == report["sends"], 2)
    assert report["confirmed"] is False and report["amcl_messages"] == 0
    assert report["sends"] >= 2 and took < 5.0
    assert report["set_initial_pose"]["called"] is False
    assert "does not exist" in report["set_initial_pose"]["answer"]
