"""The ArUco marker baseline of §4.3 (Table 3, "ArUco marker").

Six 20 cm tags, two per corridor section at the middle of the section
(:func:`initcli.sim.markers.place_markers`); the robot explores by wall following exactly as
``bim-init run`` does (§4.3: "using the same wall following based motion planning algorithm")
and localises "by decoding the unique marker": the first tag decoded gives the pose, from that one
tag (``cv2.solvePnP`` with ``SOLVEPNP_IPPE_SQUARE``). The run gives up after
``limits.max_distance`` metres (150 m, §4.3) or ``limits.max_time`` seconds.
"""

from __future__ import annotations

import time

import numpy as np

from bimtools.site.load import Site
from initcli.baselines.drive import WallFollowingExplorer
from initcli.baselines.outcome import LocalisationOutcome
from initcli.config import SessionConfig
from initcli.core.geometry import Pose2D
from initcli.core.marker_pose import robot_pose_from_marker
from initcli.session.setup import SimSetup, camera_of
from initcli.sim.markers import Marker, MarkerDetector, MarkerParams, place_markers
from initcli.sim.scenario import Circulation

__all__ = ["MarkerParams", "deploy_markers", "run_markers"]

METHOD = "markers"


def deploy_markers(config: SessionConfig, site: Site, storey: str, params: MarkerParams) -> list[Marker]:
    """The tags of §4.3 on ``storey``: ``params.count`` of ``params.size``, at ``params.height``
    or else the camera's height."""
    model = site.storeys[storey]
    height = params.height if params.height is not None else float(config.camera.pose.z)
    return place_markers(model, Circulation.of(model), params.count, size=params.size, height=height)


def run_markers(
    config: SessionConfig,
    site: Site,
    setup: SimSetup,
    rng: np.random.Generator,
    params: MarkerParams | None = None,
) -> LocalisationOutcome:
    """One marker-baseline attempt from ``setup.start`` (§4.3).

    Wall following at the control rate; at the camera rate (``detector.rate``) the simulated ArUco
    detector looks from the true pose (it only hands over noisy corner pixels, misses with
    ``sim.miss_rate``). At the first image with a decoded tag the robot claims the pose that tag
    gives (the largest in the image if several are decoded at once); ``features`` is the number of tags
    decoded in that image. Success is not judged here: ``bim-init eval`` compares ``pose`` with
    ``truth``.
    """
    started = time.perf_counter()
    params = params or MarkerParams()
    markers = deploy_markers(config, site, setup.storey, params)
    by_id = {m.id: m for m in markers}
    intrinsics, mount = camera_of(config)
    detector = MarkerDetector(markers, intrinsics, mount, setup.world, params, rng, config.sim.miss_rate)
    explorer = WallFollowingExplorer(config)
    driver = setup.driver
    every = max(1, round(driver.control_rate / config.detector.rate))
    limits = config.limits

    def outcome(
        localised: bool, reason: str, pose: Pose2D | None = None, features: int = 0
    ) -> LocalisationOutcome:
        return LocalisationOutcome(
            method=METHOD,
            localised=localised,
            reason=reason,
            pose=pose,
            truth=frame.truth,
            distance_m=float(driver.distance),
            duration_s=float(frame.t),
            features=features,
            wall_seconds=time.perf_counter() - started,
        )

    frame = driver.start()
    step = 0
    while True:
        if step % every == 0 and frame.truth is not None:
            seen = detector.detect(frame.truth, frame.t)
            if seen:
                nearest = max(seen, key=lambda i: (_apparent_size(seen[i]), -i))
                pose = robot_pose_from_marker(seen[nearest], by_id[nearest], intrinsics, mount)
                return outcome(True, f"decoded marker {nearest}", pose, len(seen))
        if driver.distance > limits.max_distance:
            return outcome(False, f"no marker decoded within {limits.max_distance:g} m")
        if frame.t > limits.max_time:
            return outcome(False, f"no marker decoded within {limits.max_time:g} s")
        v, w = explorer.command(frame)
        frame = driver.step(v, w)
        step += 1


def _apparent_size(corners_px: np.ndarray) -> float:
    """Mean side length of a decoded tag in pixels (the nearest tag looks the largest)."""
    return float(np.linalg.norm(corners_px - np.roll(corners_px, -1, axis=0), axis=1).mean())
