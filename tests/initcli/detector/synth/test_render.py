"""The numpy raycaster: a lift-lobby view and its depth against Eq. 1."""

from __future__ import annotations

import json
import math

import jsonschema
import numpy as np
import pytest

from bimtools.site.load import StoreyModel, load_site
from initcli.core.geometry.projection import CameraMount, detections_to_odom
from initcli.core.geometry.se2 import Pose2D
from initcli.detector.runtime import Detection
from initcli.detector.synth.render import render_view
from initcli.detector.synth.scene import Camera, Scene, camera_pose_in_world
from initcli.sim.rendered_camera import detections_to_objects, window_depth
from tests.helpers import SCHEMAS


@pytest.fixture(scope="module")
def storey_a(site_a) -> StoreyModel:
    return next(iter(load_site(site_a).storeys.values()))


def test_lift_lobby_view(storey_a):
    """Facing the three lift doors of block_a from the lobby: three lift boxes, depth = distance."""
    scene = Scene.from_storey(storey_a)
    camera = Camera.from_fov(320, 240, 90.0, z=1.0)
    lifts = [f for f in scene.features if f.class_name == "lift"]
    mid = lifts[1]
    pose = (
        mid.x + 3.0 * mid.normal[0],
        mid.y + 3.0 * mid.normal[1],
        math.atan2(-mid.normal[1], -mid.normal[0]),
    )
    view = render_view(scene, pose, camera)
    assert view.rgb.shape == (240, 320, 3) and view.rgb.dtype == np.uint8
    assert view.depth.shape == (240, 320) and view.depth.dtype == np.float32
    seen = {scene.features[v.index].id: v for v in view.features}
    for f in lifts:
        assert f.id in seen, f"lift {f.id} not visible"
        v = seen[f.id]
        assert v.class_name == "lift" and v.visible_fraction > 0.95
        u1, v1, u2, v2 = v.box
        cu, cv = int((u1 + u2) / 2), int((v1 + v2) / 2)
        assert view.ids[cv, cu] == v.index
    centre = seen[mid.id]
    u1, v1, u2, v2 = centre.box
    # a 1.1 m wide, 2.1 m tall door at 3 m with fx = fy = 160 px
    assert u2 - u1 == pytest.approx(160 * 1.1 / 3.0, abs=2.0)
    assert v2 - v1 == pytest.approx(160 * 2.1 / 3.0, abs=2.0)
    assert window_depth(view.depth, (u1 + u2) / 2, (v1 + v2) / 2, 2) == pytest.approx(3.0, abs=0.02)
    # the same image twice: render_view is a pure function
    assert np.array_equal(render_view(scene, pose, camera).rgb, view.rgb)


def test_rendered_depth_closes_eq1(storey_a):
    """Box centre + window depth through Eq. 1-2 lands on the feature's position in the BIM."""
    scene = Scene.from_storey(storey_a)
    mount = CameraMount(x=0.2, z=1.0)
    camera = Camera.from_fov(320, 240, 90.0, z=mount.z)
    door = next(f for f in scene.features if f.class_name == "door" and 10 < f.x < 50)
    n, t = np.array(door.normal), np.array([-door.normal[1], door.normal[0]])
    xy = np.array([door.x, door.y]) + 1.4 * n + 3.0 * t  # in the 1.8 m corridor, 3 m along it
    to_door = np.array([door.x, door.y]) - xy
    robot = (float(xy[0]), float(xy[1]), math.atan2(to_door[1], to_door[0]) + 0.1)
    view = render_view(scene, camera_pose_in_world(robot, mount), camera)
    vis = next(v for v in view.features if v.feature_id == door.id)
    objects = detections_to_objects([Detection("door", 0.9, vis.box, 0)], view.depth, window=2)
    obj = objects[0]
    point = detections_to_odom(
        np.array([obj["bbox"]]), np.array([obj["depth"]]), camera.intrinsics(), mount, Pose2D(*robot)
    )[0]
    assert math.hypot(point[0] - door.x, point[1] - door.y) < 0.1
    schema = json.loads((SCHEMAS / "detection_log.schema.json").read_text())
    record = {"type": "detections", "t": 0.0, "pose": {"x": 0.0, "y": 0.0, "yaw": 0.0}, "objects": objects}
    jsonschema.validate(record, schema)
