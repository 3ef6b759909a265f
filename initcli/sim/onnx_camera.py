"""``detector: {kind: onnx}``: the simulated camera renders the view at the robot's true pose and a
real network (ONNX, the shipped default or the user's) detects doors, lifts and stairs in it; the
rendered depth (with D455-like noise) gives the depth of Eq. 1. The whole sensor-to-pose loop with
a network in it.

It takes the settings it needs (the ``detector:`` and ``camera:`` sections') as values: the simulator
does not import the session config."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import StoreyModel
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import DetectedObject
from initcli.sim.world import SimWorld

__all__ = ["OnnxCamera", "OnnxCameraSpec"]


@dataclass(frozen=True)
class OnnxCameraSpec:
    """The network and the rendered depth camera: ``detector.model``, ``detector.score_threshold``
    (the network's confidence here), ``detector.classes``, ``camera.depth_window``,
    ``camera.depth_noise`` and the depth camera's range ``[camera.min_range, camera.range]``."""

    model: str | Path
    score_threshold: float
    depth_window: int
    depth_noise: float
    min_range: float  # m
    max_range: float  # m
    classes: Mapping[str, str] = field(default_factory=dict)


class OnnxCamera:
    def __init__(
        self,
        spec: OnnxCameraSpec,
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
                model=spec.model,
                score_threshold=spec.score_threshold,
                window=int(spec.depth_window),
                depth_noise=spec.depth_noise,
                min_depth=spec.min_range,
                max_depth=spec.max_range,
                class_map=spec.classes,
                rng=rng,
            )
        except InputError as exc:
            raise InputError(f"detector.model: {exc}") from None

    def detect(self, truth: Pose2D, t: float) -> list[DetectedObject]:
        observation = self.camera.observe((truth.x, truth.y, truth.yaw), self._clutter(self.world, t))
        return self._to_objects(observation.objects)
