"""The camera and detector in the loop: render the view at the robot's pose, run the ONNX detector,
and turn its boxes plus the rendered depth into detection-log objects (the input of Eq. 1).

``{"class", "score", "bbox": [u1, v1, u2, v2], "depth"}`` is one object of a ``detections``
record of the detection log (``schemas/detection_log.schema.json``); ``depth`` is the mean of
the valid depth pixels in the ``(2n+1) x (2n+1)`` window at the box centre (paper §3.3.1),
``None`` when none is valid. No torch here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bimtools.site.load import StoreyModel
from initcli.core.geometry.depth import window_depth
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.detector import DETECTOR_CONFIDENCE
from initcli.detector.runtime import Detection, Detector
from initcli.detector.synth.look import Look
from initcli.detector.synth.render import View, render_view
from initcli.detector.synth.scene import (
    CLUTTER_BOX,
    CLUTTER_PERSON,
    Camera,
    Clutter,
    Scene,
    camera_pose_in_world,
)
from initcli.io.detection_log import DetectedObject
from initcli.sim.world import SimWorld
from initcli.storey.outlines import box_edges

__all__ = [
    "Observation",
    "RenderedCamera",
    "d455_depth",
    "detections_to_objects",
    "to_detected_objects",
    "world_clutter",
]


def detections_to_objects(
    detections: Sequence[Detection],
    depth: np.ndarray,
    window: int = 2,
    class_map: Mapping[str, str] | None = None,
    min_depth: float = 0.0,
    max_depth: float = math.inf,
) -> list[dict]:
    """Detections + a depth image aligned with the colour image -> detection-log objects."""
    cmap = {str(k).strip().lower(): str(v) for k, v in (class_map or {}).items()}
    out = []
    for d in detections:
        u1, v1, u2, v2 = d.box
        z = window_depth(depth, (u1 + u2) / 2.0, (v1 + v2) / 2.0, window, min_depth, max_depth)
        out.append(
            {
                "class": cmap.get(d.class_name.strip().lower(), d.class_name),
                "score": round(float(d.score), 4),
                "bbox": [round(float(u1), 2), round(float(v1), 2), round(float(u2), 2), round(float(v2), 2)],
                "depth": None if z is None else round(z, 4),
            }
        )
    return out


def to_detected_objects(objects: Sequence[dict]) -> list[DetectedObject]:
    """Detection-log objects (dicts) -> :class:`initcli.io.detection_log.DetectedObject`."""
    return [DetectedObject(o["class"], float(o["score"]), tuple(o["bbox"]), o["depth"]) for o in objects]


def d455_depth(
    depth: np.ndarray, rng: np.random.Generator, noise_quad: float, min_depth: float, max_depth: float
) -> np.ndarray:
    """A depth-camera reading of a true depth image: sigma = noise_quad * d^2 (``camera.depth_noise``;
    D455: ~2 % at 4 m), 0 (no return) outside the camera's range [min_depth, max_depth] m."""
    d = depth.astype(np.float32)
    noisy = d + rng.normal(0.0, 1.0, d.shape).astype(np.float32) * (noise_quad * d * d)
    return np.where((d >= min_depth) & (d <= max_depth), noisy, 0.0).astype(np.float32)


def world_clutter(
    world: SimWorld, t: float, clutter_height: float = 1.2, person_height: float = 1.75
) -> Clutter:
    """The simulator's unmapped clutter boxes and its walking workers at time ``t``, for rendering."""
    rings = [np.asarray(b, dtype=float) for b in world.clutter]
    tops = [clutter_height] * len(rings)
    kinds = [CLUTTER_BOX] * len(rings)
    for w in world.workers:
        x, y = w.position(t)
        edges = box_edges(x, y, w.radius, w.radius)
        rings.append(np.vstack([edges[:, 0:2], edges[-1:, 2:4]]))
        tops.append(person_height)
        kinds.append(CLUTTER_PERSON)
    palette = np.array([[170.0, 120.0, 70.0], [60.0, 90.0, 150.0]])
    return Clutter.from_rings(rings, tops, kinds, palette[[int(k == CLUTTER_PERSON) for k in kinds]])


@dataclass
class Observation:
    view: View
    detections: list[Detection]
    objects: list[dict]  # detection-log objects


class RenderedCamera:
    """A simulated RGB-D camera with a real network: ``observe(robot_pose) -> Observation``.

    The camera is ``mount`` on the robot (its height ``mount.z`` above the floor; pitch and roll
    are taken as 0); the view is rendered with :func:`render_view`, passed to the ONNX
    :class:`Detector` and converted with :func:`detections_to_objects` (the rendered depth,
    optionally with D455 noise when ``rng`` is given). ``min_depth`` and ``max_depth`` are the depth
    camera's range (``camera.min_range`` and ``camera.range`` in a session); the defaults, 0 and
    infinity, are a camera without limits.
    """

    def __init__(
        self,
        scene: Scene,
        intrinsics: CameraIntrinsics,
        mount: CameraMount,
        detector: Detector,
        window: int = 2,
        depth_noise: float = 0.0,
        min_depth: float = 0.0,
        max_depth: float = math.inf,
        look: Look | None = None,
        class_map: Mapping[str, str] | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        self.scene = scene
        self.camera = Camera.from_intrinsics(intrinsics, z=mount.z)
        self.mount = mount
        self.detector = detector
        self.window = window
        self.depth_noise = depth_noise
        self.min_depth, self.max_depth = min_depth, max_depth
        self.look = look
        self.class_map = class_map
        self.rng = rng

    @staticmethod
    def from_storey(
        storey: StoreyModel,
        intrinsics: CameraIntrinsics,
        mount: CameraMount,
        model: str | Path = "default",
        score_threshold: float = DETECTOR_CONFIDENCE,
        threads: int = 2,
        **kwargs: object,
    ) -> RenderedCamera:
        detector = Detector(model, conf=score_threshold, threads=threads)
        return RenderedCamera(Scene.from_storey(storey), intrinsics, mount, detector, **kwargs)  # type: ignore[arg-type]

    def observe(self, robot_pose: tuple[float, float, float], clutter: Clutter | None = None) -> Observation:
        """Render at the robot's true pose in the BIM frame (with ``clutter``, e.g. :func:`world_clutter`,
        in front of the walls), detect, measure depth."""
        scene = self.scene if clutter is None else self.scene.with_extras(clutter=clutter)
        view = render_view(scene, camera_pose_in_world(robot_pose, self.mount), self.camera, self.look)
        depth = view.depth
        if self.rng is not None and self.depth_noise > 0:
            lo = self.min_depth if self.min_depth > 0 else 0.0
            hi = self.max_depth if math.isfinite(self.max_depth) else 1e9
            depth = d455_depth(depth, self.rng, self.depth_noise, lo, hi)
        detections = self.detector.detect(view.bgr)
        objects = detections_to_objects(
            detections, depth, self.window, self.class_map, self.min_depth, self.max_depth
        )
        return Observation(view, detections, objects)
