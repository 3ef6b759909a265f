"""The rosbridge driver fed from a recorded bag by a loopback rosbridge server: sensors in, Twist out,
and the robot stopped on error and Ctrl-C."""

from __future__ import annotations

import threading
import time

import pytest

from benchmarks._recordings import CAMERA, MOUNT, POINTS, make_recording, write
from bimkit.errors import InputError
from initcli.config import RosbridgeSection
from initcli.ros.bag_source import BagSource
from initcli.ros.msgdefs import to_dict
from tests.initcli.ros.rosbridge_server import RosbridgeServer

pytest.importorskip("roslibpy")

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
        assert server.wait_for(lambda: len(server.of("subscribe")) == 4)
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
        server.wait_for(lambda: len(server.of("subscribe")) == 4)
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
        server.wait_for(lambda: len(server.of("subscribe")) == 4)
        server.send("/odom", {"pose": {"pose": {"position": {"x": 1.0}, "orientation": {"w": 1.0}}}})
        driver.start()
        driver.step(0.4, 0.0)
        driver.close()
        time.sleep(0.2)
        assert server.published("/cmd_vel") == [] and not any(
            o["topic"] == "/cmd_vel" for o in server.of("advertise")
        )
