"""The rendered camera: the shipped model in the loop on block_b (a layout it never saw; detect with
onnxruntime, depth at the box centres), and the windowed depth lookup."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.site.load import load_site
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.detector import DEFAULT_MODEL
from initcli.detector.layouts import iou_matrix
from initcli.detector.runtime import Detector
from initcli.detector.synth.render import render_view
from initcli.detector.synth.scene import Camera, Clutter, Scene, camera_pose_in_world
from initcli.sim.rendered_camera import RenderedCamera, to_detected_objects, window_depth
from tests.helpers import SAMPLES

pytestmark = pytest.mark.skipif(
    not DEFAULT_MODEL.exists(), reason="the default model has not been trained yet"
)


@pytest.fixture(scope="module")
def storey_b(tmp_path_factory):
    out = tmp_path_factory.mktemp("default_model") / "block_b"
    write_site(out, extract_site(SAMPLES / "block_b.ifc"), preview=False)
    return next(iter(load_site(out).storeys.values()))


def _lobby_pose(scene: Scene, distance: float) -> tuple[float, float, float]:
    lifts = [f for f in scene.features if f.class_name == "lift"]
    mid = lifts[len(lifts) // 2]
    return (
        mid.x + distance * mid.normal[0],
        mid.y + distance * mid.normal[1],
        math.atan2(-mid.normal[1], -mid.normal[0]),
    )


def test_default_model_file():
    assert DEFAULT_MODEL.stat().st_size <= 15_000_000
    card = json.loads(DEFAULT_MODEL.with_suffix(".json").read_text())
    assert card["evaluation"]["map50"] is not None
    assert card["bytes"] == DEFAULT_MODEL.stat().st_size
    det = Detector("default")
    assert det.names == ["door", "lift", "stairs"] and det.layout == "yolov8"
    assert det.input_size == tuple(card["input"][2:])  # the card describes the shipped graph


def test_lifts_found_with_depth(storey_b):
    """In block_b's lift lobby the default model finds the lifts the renderer shows, with the right depth."""
    intrinsics = CameraIntrinsics(320.0, 320.0, 320.0, 240.0, 640, 480)  # the session's default camera
    mount = CameraMount(x=0.0, z=1.0)
    sensor = RenderedCamera.from_storey(storey_b, intrinsics, mount, "default", score_threshold=0.4)
    robot = _lobby_pose(sensor.scene, 3.5)
    obs = sensor.observe(robot)
    truth = [v for v in obs.view.features if v.class_name == "lift" and v.visible_fraction > 0.9]
    assert len(truth) >= 2
    lifts = [o for o in obs.objects if o["class"] == "lift"]
    ious = iou_matrix(np.array([t.box for t in truth]), np.array([o["bbox"] for o in lifts]).reshape(-1, 4))
    assert (ious.max(axis=1) >= 0.5).sum() >= len(truth) - 1, (truth, lifts)
    for o in lifts:
        assert o["depth"] == pytest.approx(3.5, abs=0.3)
    assert all(d.depth is not None for d in to_detected_objects(lifts))


def test_person_in_front_hides_a_lift(storey_b):
    scene = Scene.from_storey(storey_b)
    camera = Camera.from_fov(640, 480, 90.0, z=1.0)
    pose = camera_pose_in_world(_lobby_pose(scene, 3.5), CameraMount())
    lifts = [f for f in scene.features if f.class_name == "lift"]
    mid = lifts[len(lifts) // 2]
    person = Clutter.from_boxes(
        [(mid.x + 1.0 * mid.normal[0], mid.y + 1.0 * mid.normal[1], 0.3, 0.3, 0.0)], [2.2]
    )

    view = render_view(scene.with_extras(clutter=person), pose, camera)
    hidden = [v for v in view.features if v.feature_id == mid.id]
    assert not hidden or hidden[0].visible_fraction < 0.6


def test_window_depth_ignores_invalid_pixels():
    depth = np.zeros((10, 10), dtype=np.float32)
    depth[4:7, 4:7] = 2.0
    depth[5, 5] = np.nan
    assert window_depth(depth, 5.5, 5.5, 1) == pytest.approx(2.0)
    assert window_depth(depth, 1.0, 1.0, 1) is None
    assert window_depth(depth, 5.5, 5.5, 2, max_depth=1.5) is None
    assert window_depth(depth, -3.0, 5.0, 2) is None
