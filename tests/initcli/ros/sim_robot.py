"""The simulated robot (initcli.sim) served over the loopback rosbridge test server, as a live
robot behind rosbridge looks to ``bim-init run``: odometry on the robot's clock (``header.stamp``
from 1.7e9 s, ROS 2 or ROS 1 stamps), ``/scan``, ``/detections`` (vision_msgs Humble layout,
the robot's own detector), an aligned 16UC1 depth image, CameraInfo and the camera mount on
``/tf_static`` (sent to each subscriber, as a latched topic is), driven by ``/cmd_vel``.

It steps once per ``/cmd_vel`` message (lockstep: simulated time runs as fast as the session
sends commands, 0.1 s a step; without a command for 0.2 s the odometry is sent again, the clock
running on). Once the session advertises ``/initialpose`` the robot drives on
by itself (``creep``, as a person or Nav2 would), in real time times ``speed``, so the pose sent
must be carried forward. :meth:`truth` is its true pose at a stamp; ``stop_after`` steps: the
odometry stops (the robot's driver died).

``has_camera=False``: a robot without a camera (no CameraInfo, detections or depth, and rosapi lists
none of them). ``laser``: the laser's mount on the base (x, y, yaw): its scans are cast from there,
in its own frame ``laser`` (sent on ``/tf_static`` as base_link -> laser), misses as ``null`` (as
rosbridge sends inf) and every 50th beam 0 (no return either).
"""

from __future__ import annotations

import base64
import math
import queue
import threading
import time
from typing import Any

import numpy as np

from bimtools.site.load import Site
from initcli.config import SessionConfig
from initcli.config.building import choose_storey
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import SensorFrame
from initcli.ros.bag_writer import OPTICAL_FRAME, camera_info, camera_tf, transform_stamped
from initcli.ros.nav2 import pose_dict, stamp_dict
from initcli.ros.tf import yaw_quaternion
from initcli.sim.build import build_sim
from tests.initcli.ros.rosbridge_server import RosbridgeServer

T0 = 1_700_000_000.0
STEP_S = 0.1  # the simulator's control period
KEEPALIVE_S = 0.2  # s without a command: the odometry is sent again (the robot stands)


class SimRobot:
    def __init__(
        self,
        server: RosbridgeServer,
        config: SessionConfig,
        site: Site,
        seed: int,
        start: Pose2D,
        ros1: bool = False,
        creep: tuple[float, float] = (0.3, 0.15),
        speed: float = 1.0,
        stop_after: int | None = None,
        has_camera: bool = True,
        laser: Pose2D | None = None,
    ) -> None:
        simulated, _ = choose_storey(config, site)
        self.sim = build_sim(config, site, simulated, seed, start).driver
        self.server, self.ros1, self.creep, self.speed = server, ros1, creep, speed
        self.stop_after = stop_after
        self.has_camera, self.laser = has_camera, laser
        server.robot_topics |= {"/odom", "/scan", "/tf_static"}
        if has_camera:
            server.robot_topics |= {"/detections", "/camera/depth/image", "/camera/color/camera_info"}
        self.window = int(config.camera.depth_window)
        self.truths: list[tuple[float, Pose2D]] = []  # (stamp, true pose in the BIM/map frame)
        self.received: list[tuple[float, dict]] = []  # each /initialpose: (the robot's clock then, message)
        self.commands: queue.Queue[tuple[float, float] | None] = queue.Queue()
        self.creeping = threading.Event()
        self.steps = 0
        self.idle = 0.0  # s of the robot's clock spent waiting for a command
        self._stop = threading.Event()
        server.hooks[("publish", "/cmd_vel")] = self._on_cmd_vel
        server.hooks[("advertise", "/initialpose")] = lambda _: self.creeping.set()
        server.hooks[("subscribe", "/tf_static")] = lambda _: self._tf_static()  # latched
        server.hooks[("publish", "/initialpose")] = lambda op: self.received.append(
            (self.truths[-1][0], op["msg"])
        )
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> SimRobot:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self.commands.put(None)
        self._thread.join(timeout=5)

    def truth(self, stamp: float) -> Pose2D:
        """The true pose at the simulated step nearest ``stamp``."""
        return min(self.truths, key=lambda s: abs(s[0] - stamp))[1]

    def _on_cmd_vel(self, op: dict[str, Any]) -> None:
        msg = op["msg"]
        self.commands.put((float(msg["linear"]["x"]), float(msg["angular"]["z"])))

    # -- the robot's side ---------------------------------------------------------------------------

    def _run(self) -> None:
        deadline = time.monotonic() + 10
        while len(self.server.subscriptions.get("/odom", [])) == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        frame = self.sim.start()
        self._publish(frame)
        while not self._stop.is_set():
            if self.creeping.is_set():
                time.sleep(STEP_S / self.speed)
                frame = self.sim.step(*self.creep)
                self._publish(frame)
                continue
            try:
                command = self.commands.get(timeout=KEEPALIVE_S)
            except queue.Empty:  # no command: the robot stands, its clock and odometry go on
                self.idle += KEEPALIVE_S
                self._publish(frame, image=False)
                continue
            if command is None:
                return
            if not self.creeping.is_set():
                frame = self.sim.step(*command)
                self._publish(frame)

    def _publish(self, frame: SensorFrame, image: bool = True) -> None:
        stamp = T0 + frame.t + self.idle
        self.steps += 1
        assert frame.truth is not None
        self.truths.append((stamp, frame.truth))
        if self.stop_after is not None and self.steps > self.stop_after:
            return
        head = {"stamp": stamp_dict(stamp, self.ros1), "frame_id": "odom"}
        o = frame.odom
        self.server.send(
            "/odom",
            {"header": head, "child_frame_id": "base_link", "pose": {"pose": pose_dict(o.x, o.y, o.yaw)}},
        )
        if frame.scan is not None and self.laser is not None:
            self.server.send("/scan", self._laser_scan(frame, head))
        elif frame.scan is not None:
            s = frame.scan
            self.server.send(
                "/scan",
                {
                    "header": {**head, "frame_id": "base_link"},
                    "angle_min": s.angle_min,
                    "angle_increment": s.angle_increment,
                    "range_min": 0.05,
                    "range_max": s.range_max,
                    "ranges": [float(r) for r in s.ranges],
                },
            )
        if not self.has_camera:
            return
        camera_head = {"stamp": stamp_dict(stamp, self.ros1), "frame_id": OPTICAL_FRAME}
        self.server.send(
            "/camera/color/camera_info", {**camera_info(stamp, self.sim.camera), "header": camera_head}
        )
        if image and frame.detections is not None:
            self._image(stamp, frame)

    def _laser_scan(self, frame: SensorFrame, head: dict[str, Any]) -> dict[str, Any]:
        """The scan the laser at ``self.laser`` reads from the true pose, in its own frame."""
        assert frame.truth is not None and frame.scan is not None and self.laser is not None
        s = frame.scan
        at = frame.truth * self.laser
        angles = s.angle_min + s.angle_increment * np.arange(len(s.ranges))
        ranges = self.sim.world.raycast(np.array([at.x, at.y]), angles + at.yaw, s.range_max, frame.t)
        out: list[float | None] = [None if r >= s.range_max else float(r) for r in ranges]
        out[::50] = [0.0] * len(out[::50])
        return {
            "header": {**head, "frame_id": "laser"},
            "angle_min": s.angle_min,
            "angle_max": s.angle_min + s.angle_increment * (len(out) - 1),
            "angle_increment": s.angle_increment,
            "range_min": 0.05,
            "range_max": s.range_max,
            "ranges": out,
        }

    def _tf_static(self) -> None:
        transforms = camera_tf(T0, self.sim.mount, base="base_link") if self.has_camera else []
        if self.laser is not None:
            m = self.laser
            transforms.append(
                transform_stamped(T0, "base_link", "laser", (m.x, m.y, 0.3), yaw_quaternion(m.yaw))
            )
        for tr in transforms:
            tr["header"]["stamp"] = stamp_dict(T0, self.ros1)
        self.server.send("/tf_static", {"transforms": transforms})

    def _image(self, stamp: float, frame: SensorFrame) -> None:
        head = {"stamp": stamp_dict(stamp, self.ros1), "frame_id": OPTICAL_FRAME}
        cam = self.sim.camera
        objects = [o for o in frame.detections or [] if o.depth is not None]
        # A full-size depth image only when there is a box to read (each box's window at its depth).
        h, w = (cam.height, cam.width) if objects else (1, 1)
        depth = np.zeros((h, w), "<u2")
        dets = []
        for o in objects:
            u1, v1, u2, v2 = o.bbox
            cu, cv = int(math.floor((u1 + u2) / 2)), int(math.floor((v1 + v2) / 2))
            if not (0 <= cu < w and 0 <= cv < h):
                continue
            k = self.window
            depth[max(0, cv - k) : cv + k + 1, max(0, cu - k) : cu + k + 1] = round(
                float(o.depth or 0) * 1000
            )
            dets.append(
                {
                    "header": head,
                    "results": [{"hypothesis": {"class_id": o.cls, "score": o.score}}],
                    "bbox": {
                        "center": {"position": {"x": (u1 + u2) / 2, "y": (v1 + v2) / 2}, "theta": 0.0},
                        "size_x": u2 - u1,
                        "size_y": v2 - v1,
                    },
                    "id": "",
                }
            )
        data = base64.b64encode(depth.tobytes()).decode()
        self.server.send(
            "/camera/depth/image",
            {
                "header": head,
                "height": h,
                "width": w,
                "encoding": "16UC1",
                "is_bigendian": 0,
                "step": 2 * w,
                "data": data,
            },
        )
        self.server.send("/detections", {"header": head, "detections": dets})
