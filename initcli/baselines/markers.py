"""The ArUco marker baseline of §4.3 (Table 3, "ArUco marker").

Six 20 cm tags, two per corridor section at the middle of the section
(:func:`initcli.sim.markers.place_markers`); the robot explores by wall following exactly as
``bim-init run`` does (§4.3: "using the same wall following based motion planning algorithm")
and localises "by decoding the unique marker": the first tag decoded gives the pose, from that one
tag (``cv2.solvePnP`` with ``SOLVEPNP_IPPE_SQUARE``). The run gives up after
``limits.max_distance`` metres (150 m, §4.3) or ``limits.max_time`` seconds.
"""

from __future__ import annotations

import numpy as np

from bimtools.site.load import Site
from initcli.baselines.drive import drive_attempts, limit_passed
from initcli.baselines.outcome import LocalisationOutcome
from initcli.config import SessionConfig, camera_of
from initcli.core.features.marker_pose import robot_pose_from_marker
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import SensorFrame
from initcli.sim.build import SimSetup
from initcli.sim.markers import Marker, MarkerDetector, MarkerParams, place_markers
from initcli.storey.circulation import Circulation

__all__ = ["MarkerAttempt", "MarkerParams", "deploy_markers", "run_markers"]

METHOD = "markers"


def deploy_markers(config: SessionConfig, site: Site, storey: str, params: MarkerParams) -> list[Marker]:
    """The tags of §4.3 on ``storey``: ``params.count`` of ``params.size``, at ``params.height``
    or else the camera's height."""
    model = site.storeys[storey]
    height = params.height if params.height is not None else float(config.camera.pose.z)
    return place_markers(model, Circulation.of(model), params.count, size=params.size, height=height)


class MarkerAttempt:
    """The marker baseline along the wall-following drive (a
    :class:`~initcli.baselines.drive.BaselineAttempt`): at the camera rate (``detector.rate``) the
    simulated ArUco detector looks from the true pose (it only hands over noisy corner pixels,
    misses with ``sim.miss_rate``); the first image with a decoded tag gives the pose."""

    def __init__(
        self,
        config: SessionConfig,
        site: Site,
        setup: SimSetup,
        rng: np.random.Generator,
        params: MarkerParams | None = None,
    ) -> None:
        params = params or MarkerParams()
        markers = deploy_markers(config, site, setup.storey, params)
        self.by_id = {m.id: m for m in markers}
        self.intrinsics, self.mount = camera_of(config)
        self.detector = MarkerDetector(
            markers, self.intrinsics, self.mount, setup.world, params, rng, config.sim.miss_rate
        )
        self.driver = setup.driver
        self.every = max(1, round(self.driver.control_rate / config.detector.rate))
        self.config = config

    def _outcome(
        self, frame: SensorFrame, localised: bool, reason: str, pose: Pose2D | None = None, features: int = 0
    ) -> LocalisationOutcome:
        return LocalisationOutcome(
            method=METHOD,
            localised=localised,
            reason=reason,
            pose=pose,
            truth=frame.truth,
            distance_m=float(self.driver.distance),
            duration_s=float(frame.t),
            features=features,
        )

    def start(self, frame: SensorFrame) -> LocalisationOutcome | None:
        return self.observe(frame, 0)

    def observe(self, frame: SensorFrame, step: int) -> LocalisationOutcome | None:
        if step % self.every == 0 and frame.truth is not None:
            seen = self.detector.detect(frame.truth, frame.t)
            if seen:
                nearest = max(seen, key=lambda i: (_apparent_size(seen[i]), -i))
                pose = robot_pose_from_marker(seen[nearest], self.by_id[nearest], self.intrinsics, self.mount)
                return self._outcome(frame, True, f"decoded marker {nearest}", pose, len(seen))
        passed = limit_passed(self.config, self.driver.distance, frame.t)
        if passed is not None:
            return self._outcome(frame, False, f"no marker decoded within {passed}")
        return None


def run_markers(
    config: SessionConfig,
    site: Site,
    setup: SimSetup,
    rng: np.random.Generator,
    params: MarkerParams | None = None,
) -> LocalisationOutcome:
    """One marker-baseline attempt from ``setup.start`` (§4.3): wall following at the control rate
    until the first image with a decoded tag, whose pose the robot claims (the largest tag in the
    image if several are decoded at once; ``features`` is the number decoded in that image).
    Success is not judged here: ``bim-init eval`` compares ``pose`` with ``truth``.
    """
    return drive_attempts(config, setup.driver, [MarkerAttempt(config, site, setup, rng, params)])[0]


def _apparent_size(corners_px: np.ndarray) -> float:
    """Mean side length of a decoded tag in pixels (the nearest tag looks the largest)."""
    return float(np.linalg.norm(corners_px - np.roll(corners_px, -1, axis=0), axis=1).mean())
