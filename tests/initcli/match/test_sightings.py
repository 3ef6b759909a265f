"""The session's image-by-image sightings are those ``bim-init match`` computes from its log."""

from __future__ import annotations

import math

import numpy as np

from initcli.config.session import LidarSection
from initcli.core.features.classes import ClassMap
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import LaserScan, SensorFrame
from initcli.io.detection_log import DetectedObject, Detections, Meta, Scan, read_log
from initcli.match.pipeline import MatchOptions
from initcli.match.sightings import image_sightings, sightings_from_log
from initcli.session.perception import Perception

SCAN_LOG_EVERY = LidarSection().log_every

CAMERA = CameraIntrinsics(320.0, 320.0, 320.0, 240.0, 640, 480)
MOUNT = CameraMount(x=0.2, z=1.0)


def door(u: float, depth: float | None) -> DetectedObject:
    return DetectedObject("door", 0.9, (u - 30.0, 100.0, u + 30.0, 400.0), depth)


def frames() -> list[SensorFrame]:
    scan = LaserScan(-math.pi, 2 * math.pi / 8, 10.0, np.full(8, 4.0))
    images = [
        [door(320.0, 3.0), door(1.0, 4.0)],  # the second is cut by the image border
        [],  # an image with nothing in it still counts as a frame
        [door(200.0, None)],  # no depth: no sighting
        [door(500.0, 2.5)],
    ]
    out = []
    for i, objects in enumerate(images):
        pose = Pose2D(0.5 * i, 0.1 * i, 0.05 * i)
        out.append(SensorFrame(0.1 * i, pose, scan, objects))
        out.append(SensorFrame(0.1 * i + 0.05, pose, scan, None))  # a period without an image
    return out


def test_the_logged_session_replays_to_the_same_sightings(tmp_path):
    options = MatchOptions(storey=None)
    meta = Meta(camera=CAMERA, camera_pose=MOUNT, depth_window=2, source="test")
    path = tmp_path / "session.jsonl"
    perception = Perception(meta, path, ClassMap({}), options, drift_window=0.0, scan_every=SCAN_LOG_EVERY)
    for step, frame in enumerate(frames()):
        perception.record_frame(frame, step)
    perception.close()
    sightings = perception.sightings
    assert [s.frame for s in sightings] == [0, 0, 3]
    assert [s.truncated for s in sightings] == [False, True, False]
    log = read_log(path)
    assert sightings_from_log(log, ClassMap({}), options.edge_margin) == sightings
    # the file holds what the session kept, plus every SCAN_LOG_EVERY-th scan
    kept = [r for r in log.records if not isinstance(r, Scan)]
    assert kept == perception.log.records
    assert len(log.of_type(Scan)) == len(range(0, len(frames()), SCAN_LOG_EVERY))


def test_image_sightings_project_each_box_with_a_depth():
    frame = frames()[6]
    assert frame.detections is not None
    rec = Detections(frame.t, frame.odom, (door(100.0, math.inf), *frame.detections))
    (s,) = image_sightings(rec, 7, ClassMap({}), CAMERA, MOUNT, edge_margin=2.0)
    assert s.frame == 7 and s.depth == 2.5 and s.cls == "door"
    # a box right of the image centre lies to the robot's right, about depth + mount ahead
    local = frame.odom.inverse().apply(np.array([s.x, s.y]))
    assert local[1] < 0 and 2.5 < local[0] < 2.5 + MOUNT.x + 0.1
