"""The numpy raycaster, the synthetic dataset writer and the depth-to-detection helper (no torch)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml

from bimtools.errors import InputError
from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.site.load import StoreyModel, load_site
from initcli.core.geometry import Pose2D
from initcli.core.projection import CameraMount, detections_to_odom
from initcli.detector.render import render_view
from initcli.detector.runtime import Detection
from initcli.detector.scene import Camera, Scene, camera_pose_in_world
from initcli.detector.synth import SynthOptions, load_placements, render_sample, write_dataset
from initcli.sim.rendered_camera import detections_to_objects, window_depth

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_models"


@pytest.fixture(scope="module")
def site_a(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("detector_sites") / "block_a"
    write_site(out, extract_site(SAMPLES / "block_a.ifc"), preview=False)
    return out


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
    schema = json.loads((ROOT / "schemas" / "detection_log.schema.json").read_text())
    record = {"type": "detections", "t": 0.0, "pose": {"x": 0.0, "y": 0.0, "yaw": 0.0}, "objects": objects}
    jsonschema.validate(record, schema)


def test_window_depth_ignores_invalid_pixels():
    depth = np.zeros((10, 10), dtype=np.float32)
    depth[4:7, 4:7] = 2.0
    depth[5, 5] = np.nan
    assert window_depth(depth, 5.5, 5.5, 1) == pytest.approx(2.0)
    assert window_depth(depth, 1.0, 1.0, 1) is None
    assert window_depth(depth, 5.5, 5.5, 2, max_depth=1.5) is None
    assert window_depth(depth, -3.0, 5.0, 2) is None


def test_scene_needs_walls():
    with pytest.raises(InputError, match="no walls"):
        Scene.from_storey(StoreyModel("L1", 0.0, []))


def test_synth_dataset(site_a, tmp_path):
    """A small dataset: YOLO layout, normalised labels inside the image, deterministic per (seed, i)."""
    out = tmp_path / "ds"
    doc = write_dataset(
        [site_a], out, SynthOptions(images=12, width=160, height=120, seed=3, val_fraction=0.25, workers=1)
    )
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert set(data) >= {"path", "train", "val", "names"} and data["names"] == ["door", "lift", "stairs"]
    assert doc["images"] == {"train": 9, "val": 3}
    schema = json.loads((ROOT / "schemas" / "synth_manifest.schema.json").read_text())
    jsonschema.validate(json.loads((out / "synth.json").read_text()), schema)
    assert len(list((out / "images" / "train").glob("*.jpg"))) == 9
    assert len(list((out / "depth" / "val").glob("*.png"))) == 3
    rows = [line.split() for p in (out / "labels").rglob("*.txt") for line in p.read_text().splitlines()]
    assert rows, "no labels in 12 images"
    for r in rows:
        assert len(r) == 5 and r[0] in {"0", "1", "2"}
        cx, cy, w, h = map(float, r[1:])
        assert 0 <= cx - w / 2 and cx + w / 2 <= 1.0001 and 0 <= cy - h / 2 and cy + h / 2 <= 1.0001
    placements = load_placements([site_a])
    opts = SynthOptions(width=160, height=120, seed=3)
    a, b = render_sample(placements, 5, opts), render_sample(placements, 5, opts)
    assert np.array_equal(a.image_rgb, b.image_rgb) and a.pose == b.pose


def test_synth_cli_with_preview(site_a, tmp_path):
    from typer.testing import CliRunner

    from initcli.cli.detector import detector_app

    out, sheet = tmp_path / "ds", tmp_path / "sheet.png"
    args = ["synth", "--site", str(site_a), "--out", str(out), "--images", "6", "--size", "160x120"]
    result = CliRunner().invoke(detector_app, [*args, "--workers", "1", "--preview", str(sheet)])
    assert result.exit_code == 0, result.output
    assert sheet.stat().st_size > 1000 and (out / "data.yaml").exists()
    bad = CliRunner().invoke(detector_app, ["synth", "--site", str(tmp_path / "nope"), "--out", str(out)])
    assert bad.exit_code == 2 and "no such file or folder" in bad.output
    bad_size = CliRunner().invoke(detector_app, [*args, "--size", "big"])
    assert bad_size.exit_code == 2 and "--size" in bad_size.output
