"""The simulated RGB-D camera + detector ("oracle" detector with realistic errors).

Reports the BIM features in the field of view, within range, facing the camera and not hidden
behind walls, clutter or workers, as detector boxes with depth (the log format of
``bim-init match``): misses, transient false positives, class confusion, persistent phantoms
(door-like things not in the BIM) and depth noise growing with range (D455: ~2 % at 4 m).

The misses, false boxes, confusions and scores are flat rates (:class:`CameraNoise`) or drawn from a
measured :class:`~initcli.detector.profile.DetectorProfile` (``sim.detector.profile``): a feature in
view is then found with the profile's recall at its box height (scaled to the model's input, the
letterbox of this camera's image), given a class from the profile's confusion matrix and a score
from its quantiles of true boxes; each image gets a Poisson number of transient false boxes per
class at the profile's rate per image, scored from its false boxes' quantiles. The profile's
boxes are independent from image to image (its photos are), where a real camera's false boxes on
the same poster repeat from frame to frame (``sim.detector.persistent_phantoms`` models those).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.detector.profile import DetectorProfile
from initcli.io.detection_log import DetectedObject
from initcli.sim.synthetic_log import SimFeature, SyntheticParams, false_box, render_image
from initcli.sim.world import SimWorld

__all__ = ["CameraNoise", "SimulatedDetector"]


@dataclass(frozen=True)
class CameraNoise:
    miss_rate: float = 0.1
    false_positives_per_minute: float = 1.0
    confusion_rate: float = 0.02
    depth_noise_quad: float = 0.005
    pixel_noise: float = 2.0
    range: float = 6.0
    max_view_angle_deg: float = 75.0


class SimulatedDetector:
    def __init__(
        self,
        features: list[SimFeature],
        camera: CameraIntrinsics,
        mount: CameraMount,
        noise: CameraNoise,
        rate_hz: float,
        world: SimWorld,
        rng: np.random.Generator,
        profile: DetectorProfile | None = None,
    ):
        self.features = features
        self.profile = profile
        self.camera = camera
        self.mount = mount
        self.world = world
        self.rng = rng
        self.noise = noise
        self.classes = sorted({f.cls for f in features if not f.id.startswith("phantom")}) or ["door"]
        self.params = SyntheticParams(
            rate_hz=rate_hz,
            min_range=0.5,
            max_range=noise.range,
            max_view_angle=math.radians(noise.max_view_angle_deg),
            depth_noise_quad=noise.depth_noise_quad,
            pixel_noise=noise.pixel_noise,
            clip_boxes=True,
            score=0.9,
            false_positive_rate=0.0 if profile else noise.false_positives_per_minute / (60.0 * rate_hz),
            detect_probability=1.0 if profile else 1.0 - noise.miss_rate,
        )
        self.scale = profile.input_scale(camera.width, camera.height) if profile else 1.0

    def detect(self, truth: Pose2D, t: float) -> list[DetectedObject]:
        segments = self.world.segments_at(truth.x, truth.y, self.noise.range + 1.0, t)
        found = render_image(
            self.features,
            truth,
            self.camera,
            self.mount,
            self.params,
            walls=segments,
            rng=self.rng,
            classes=self.classes,
        )
        if self.profile is not None:
            return self._drawn(found, self.profile)
        out: list[DetectedObject] = []
        for obj, _source in found:
            if (
                self.noise.confusion_rate > 0
                and len(self.classes) > 1
                and self.rng.random() < self.noise.confusion_rate
            ):
                others = [c for c in self.classes if c != obj.cls]
                obj = replace(obj, cls=others[int(self.rng.integers(len(others)))])
            score = float(np.clip(self.rng.normal(0.85, 0.08), 0.3, 0.99))
            out.append(replace(obj, score=round(score, 3)))
        return out

    def _drawn(
        self, found: list[tuple[DetectedObject, str | None]], profile: DetectorProfile
    ) -> list[DetectedObject]:
        """The features in view found, classed and scored as the profile says, and its false boxes."""
        out: list[DetectedObject] = []
        for obj, _source in found:
            height = (obj.bbox[3] - obj.bbox[1]) * self.scale  # px of the model's input
            if self.rng.random() >= profile.recall_of(obj.cls, height):
                continue
            cls = profile.given_class(obj.cls, self.rng)
            out.append(replace(obj, cls=cls, score=round(profile.score(self.rng, true=True), 3)))
        for cls, rate in profile.false_boxes.items():
            for _ in range(int(self.rng.poisson(rate)) if rate > 0 else 0):
                box, depth = false_box(self.camera, self.params, self.rng)
                score = round(profile.score(self.rng, true=False), 3)
                out.append(DetectedObject(cls, score, box, depth))
        return out
