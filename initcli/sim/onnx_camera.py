"""``detector: {kind: onnx}``: the simulated camera renders the view at the robot's true pose and a
real network (ONNX, the shipped default or the user's) detects doors, lifts and stairs in it; the
rendered depth (with D455-like noise) gives the depth of Eq. 1. The whole sensor-to-pose loop with
a network in it."""

from __future__ import annotations

import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import StoreyModel
from initcli.config import SessionConfig
from initcli.core.geometry import Pose2D
from initcli.core.projection import CameraIntrinsics, CameraMount
from initcli.io.detection_log import DetectedObject
from initcli.sim.world import SimWorld


class OnnxCamera:
    def __init__(
        self,
        config: SessionConfig,
        storey: StoreyModel,
        world: SimWorld,
        camera: CameraIntrinsics,
        mount: CameraMount,
        rng: np.random.Generator,
    ):
        from initcli.sim.rendered_camera import RenderedCamera, to_detected_objects, world_clutter

        self._to_objects = to_detected_objects
        self._clutter = world_clutter
        self.world = world
        try:
            self.camera = RenderedCamera.from_storey(
                storey,
                camera,
                mount,
                model=config.detector.model,
                score_threshold=config.detector.score_threshold,
                window=int(config.camera.depth_window),
                depth_noise=config.camera.depth_noise,
                min_depth=0.3,
                max_depth=config.camera.range,
                class_map=config.detector.classes,
                rng=rng,
            )
        except InputError as exc:
            raise InputError(f"detector.model: {exc}") from None

    def detect(self, truth: Pose2D, t: float) -> list[DetectedObject]:
        observation = self.camera.observe((truth.x, truth.y, truth.yaw), self._clutter(self.world, t))
        return self._to_objects(observation.objects)
