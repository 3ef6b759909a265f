"""The rosbridge driver fed from a recorded bag by a loopback rosbridge server: sensors in, Twist out,
and the robot stopped on error and Ctrl-C."""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest

from benchmarks._recordings import CAMERA, MOUNT, POINTS, make_recording, write
from bimkit.errors import InputError
from initcli.config import RosbridgeSection
from initcli.ros.bag_source import BagSource
from initcli.ros.bag_writer import transform_stamped
from initcli.ros.msgdefs import to_dict
from initcli.ros.tf import yaw_quaternion
from tests.initcli.ros.rosbridge_server import RosbridgeServer

pytest.importorskip("roslibpy")

from initcli.ros.live_camera import live_camera  # noqa: E402
from initcli.ros.rosbridge import RosbridgeLink  # noqa: E402
from initcli.ros.rosbridge_driver import RosbridgeDriver  # noqa: E402

TOPICS = RosbridgeSection(detections_topic="/detections", depth_topic="/camera/depth/image")


def _replay(server: RosbridgeServer, bag, stop: threading.Event, odom_until: float) -> None:
    """Publish the bag's messages at 10x speed; odometry only until ``odom_until`` s into the bag."""
    with BagSource(bag) as source:
        msgs = list(source.messages(["/odom", "/scan", "/detections", "/camera/depth/image"]))
    t0 = msgs[0][1]
    start = time.monotonic()
    for topic, ns, msg in msgs:
        if stop.is_set():
            return
        dt = (ns - t0) * 1e-9
        if topic == "/odom" and dt > odom_until:
            continue
        time.sleep(max(0.0, start + dt / 10 - time.monotonic()))
        server.send(topic, to_dict(msg))


def _twists(server):
    return [(m["linear"]["x"], m["angular"]["z"]) for m in server.published("/cmd_vel")]


def test_drives_listens_and_stops_when_odometry_ends(tmp_path):
    bag = write(tmp_path, make_recording(duration=6.0), "mcap")
    stop = threading.Event()
    with RosbridgeServer() as server, RosbridgeLink("127.0.0.1", server.port) as link:
        driver = RosbridgeDriver(link, CAMERA, MOUNT, TOPICS, odom_timeout=0.3, period=0.02)
        assert server.wait_for(lambda: len(server.of("subscribe")) == 5)
        feeder = threading.Thread(target=_replay, args=(server, bag, stop, 3.0), daemon=True)
        feeder.start()
        frame = driver.start()
        assert frame.odom.distance_to(frame.odom.identity()) < 1e-9  # the odom frame starts here
        seen = []
        with pytest.raises(InputError, match="no odometry on /odom"):
            for _ in range(400):
                frame = driver.step(0.3, 0.1)
                if frame.detections:
                    seen.extend(frame.detections)
        stop.set()
        assert server.wait_for(lambda: _twists(server) and _twists(server)[-1] == (0.0, 0.0))
        twists = _twists(server)
        assert twists[0] == (0.3, 0.1) and twists[-1] == (0.0, 0.0)
        assert {o.cls for o in seen} <= set(POINTS) and seen
        assert all(o.depth is not None and o.depth > 0.3 for o in seen)
        assert driver.distance > 0.1
        assert {o["topic"]: o["type"] for o in server.of("advertise")}["/cmd_vel"] == "geometry_msgs/Twist"
        feeder.join(timeout=5)


def test_ctrl_c_stops_the_robot(tmp_path):
    with RosbridgeServer() as server, RosbridgeLink("127.0.0.1", server.port) as link:
        driver = RosbridgeDriver(link, CAMERA, MOUNT, TOPICS, period=0.01)
        server.wait_for(lambda: len(server.of("subscribe")) == 5)
        server.send("/odom", {"pose": {"pose": {"position": {"x": 1.0}, "orientation": {"w": 1.0}}}})
        with pytest.raises(KeyboardInterrupt), driver:
            driver.start()
            driver.step(0.4, 0.0)
            raise KeyboardInterrupt
        assert server.wait_for(lambda: _twists(server)[-1:] == [(0.0, 0.0)])
        assert _twists(server)[0] == (0.4, 0.0)


def test_listen_only_sends_no_twist(tmp_path):
    with RosbridgeServer() as server, RosbridgeLink("127.0.0.1", server.port) as link:
        driver = RosbridgeDriver(link, CAMERA, MOUNT, TOPICS, drive=False, period=0.01)
        server.wait_for(lambda: len(server.of("subscribe")) == 5)
        server.send("/odom", {"pose": {"pose": {"position": {"x": 1.0}, "orientation": {"w": 1.0}}}})
        driver.start()
        driver.step(0.4, 0.0)
        driver.close()
        time.sleep(0.2)
        assert server.published("/cmd_vel") == [] and not any(
            o["topic"] == "/cmd_vel" for o in server.of("advertise")
        )


def _odom() -> dict:
    return {
        "child_frame_id": "base_link",
        "pose": {"pose": {"position": {"x": 1.0}, "orientation": {"w": 1.0}}},
    }


def _scan(n: int, angle_max: float, ranges: list) -> dict:
    inc = 2 * math.pi / n
    return {
        "header": {"frame_id": "/laser"},
        "angle_min": -math.pi,
        "angle_max": angle_max,
        "angle_increment": inc,
        "range_min": 0.1,
        "range_max": 10.0,
        "ranges": ranges,
    }


def test_scans_come_into_the_base_frame_from_the_lasers_mount_and_broken_ones_are_dropped():
    """A laser turned 90 degrees (/tf_static base_link -> laser): its scans turned into the base
    frame, null, 0, below range_min and at range_max no returns; two broken scans dropped, one warning;
    a robot without a camera: no detections or depth subscribed."""
    warnings: list[str] = []
    topics = RosbridgeSection(camera_wait=2.0)
    with RosbridgeServer() as server, RosbridgeLink("127.0.0.1", server.port) as link:
        driver = RosbridgeDriver(
            link, CAMERA, MOUNT, topics, period=0.01, camera_topics=False, warn=warnings.append
        )
        assert server.wait_for(lambda: len(server.of("subscribe")) == 3)
        assert {o["topic"] for o in server.of("subscribe")} == {"/odom", "/scan", "/tf_static"}
        laser = transform_stamped(0.0, "base_link", "laser", (0.0, 0.0, 0.2), yaw_quaternion(math.pi / 2))
        server.send("/tf_static", {"transforms": [laser]})
        server.send("/odom", _odom())
        n = 720
        server.send("/scan", _scan(n, math.pi, [2.0] * (n + 5)))  # more ranges than its angles hold
        server.send("/scan", {**_scan(n, math.pi, [2.0] * n), "angle_increment": None})  # NaN
        good = [2.0] * n
        good[:4] = [None, 0.0, 0.05, 10.0]
        server.send("/scan", _scan(n, math.pi - 2 * math.pi / n, good))
        assert server.wait_for(lambda: driver._scans_in == 3)
        frame = driver.start()
        assert driver.scans_dropped == 2 and len(warnings) == 1, warnings
        assert "/scan (message 1)" in warnings[0] and "such scans are dropped" in warnings[0]
        assert frame.scan is not None and len(frame.scan.ranges) == n
        assert frame.scan.angle_min == pytest.approx(-math.pi / 2)  # turned by the mount's 90 degrees
        assert np.isnan(frame.scan.ranges[:4]).all() and (frame.scan.ranges[4:] == 2.0).all()
        assert driver.lidar_record()["mount_from"] == "/tf_static base_link -> laser"
        assert driver.lidar_mount is not None and driver.lidar_mount.yaw == pytest.approx(math.pi / 2)
        driver.close()


def test_without_rosapi_auto_keeps_the_camera_and_absent_asks_nothing():
    """auto without rosapi cannot tell, so the camera stays: after camera_wait s without CameraInfo
    the site config's camera (one warning); camera: absent asks nothing and warns nothing."""
    with RosbridgeServer() as server, RosbridgeLink("127.0.0.1", server.port) as link:
        seen = live_camera(link, RosbridgeSection(camera_wait=1.0), CAMERA, MOUNT, "base_link")
        assert not seen.absent and seen.camera == CAMERA
        assert "no CameraInfo on /camera/color/camera_info in 1 s" in seen.warnings[0]
        told = live_camera(link, RosbridgeSection(camera="absent"), CAMERA, MOUNT, "base_link")
        assert told.absent and not told.warnings and told.record()["absent_because"].endswith("absent")


def test_detections_no_detector_sends_are_dropped_with_one_warning(tmp_path):
    """A score outside [0, 1] never reaches the session (its log must stay readable): dropped, the
    first with a warning naming the topic."""
    recording = make_recording(duration=4.0)
    for m in recording.messages:
        if m.topic == "/detections":
            for det in m.value["detections"]:
                det["results"][0]["hypothesis"]["score"] = 7.0
    bag = write(tmp_path, recording, "mcap")
    warnings: list[str] = []
    stop = threading.Event()
    seen = []
    with RosbridgeServer() as server, RosbridgeLink("127.0.0.1", server.port) as link:
        driver = RosbridgeDriver(
            link, CAMERA, MOUNT, TOPICS, odom_timeout=0.3, period=0.02, warn=warnings.append
        )
        assert server.wait_for(lambda: len(server.of("subscribe")) == 5)
        feeder = threading.Thread(target=_replay, args=(server, bag, stop, 3.0), daemon=True)
        feeder.start()
        driver.start()
        with pytest.raises(InputError, match="no odometry on /odom"):
            for _ in range(400):
                seen.extend(driver.step(0.3, 0.1).detections or [])
        stop.set()
        feeder.join(timeout=5)
    assert not seen and driver.detections_dropped > 0
    dropped = [w for w in warnings if "Detection2D" in w]
    assert len(dropped) == 1 and dropped[0].startswith("/detections: a Detection2D with score 7")
