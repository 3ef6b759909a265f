"""The simulated RGB-D camera + detector ("oracle" detector with realistic errors).

Reports the BIM features in the field of view, within range, facing the camera and not hidden
behind walls, clutter or workers, as detector boxes with depth (the log format of
``bim-init match``): misses, transient false positives, class confusion, persistent phantoms
(door-like things not in the BIM) and depth noise growing with range (D455: ~2 % at 4 m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from initcli.core.geometry import Pose2D
from initcli.core.projection import CameraIntrinsics, CameraMount
from initcli.io.detection_log import DetectedObject
from initcli.sim.synthetic_log import SimFeature, SyntheticParams, render_image
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
    ):
        self.features = features
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
            false_positive_rate=noise.false_positives_per_minute / (60.0 * rate_hz),
            detect_probability=1.0 - noise.miss_rate,
        )

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
