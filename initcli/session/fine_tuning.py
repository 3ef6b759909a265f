"""Fine tuning (Eq. 18): a particle filter seeded at the rectified pose tracks the robot while it
follows the wall, until its covariance falls below the thresholds or its distance runs out.

When the filter settles, the scan decides what to keep: the rectified pose carried along by
odometry if the filter drifted away from it and the carried pose fits the scan clearly better;
a second, wider try if the filter's pose fits the map badly; the filter's pose otherwise.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from bimtools.site.load import StoreyModel
from bimtools.site.records import Feature, OccupancyGrid
from initcli.config.session import FineTuningSection
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.filters.covariance import honest_covariance
from initcli.core.filters.particle_filter import (
    FilterNoise,
    LaserModel,
    LikelihoodField,
    ParticleFilter,
    likelihood_field,
    scan_fit,
)
from initcli.core.geometry.motion import motion_delta
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.lidar.scan_jackknife import sector_jackknife
from initcli.core.navigation.wall_following import ScanView, WallFollowParams, wall_follow
from initcli.drivers.base import LaserScan, RobotDriver, SensorFrame
from initcli.session.result import SessionResult

__all__ = [
    "FineLost",
    "FineStage",
    "FineTuned",
    "FineTuning",
    "FineTuningHooks",
    "Settlement",
    "matched_pairs",
    "settle",
]


class Settlement(StrEnum):
    """What to do once the filter settled (:func:`settle`)."""

    KEEP_RECTIFIED = "keep rectified"
    RESEED = "reseed"
    LOST = "lost"
    ACCEPT = "accept"


def settle(
    estimate: Pose2D,
    fit: float,
    carried: Pose2D,
    carried_fit: float,
    reseeded: bool,
    params: FineTuningSection,
    min_scan_fit: float,
) -> Settlement:
    """What to do once the filter settled at ``estimate`` (``fit``: its fraction of the scan on the
    map), given the rectified pose ``carried`` along by odometry (``carried_fit``); ``min_scan_fit``:
    the fit a pose needs (``verification.min_fine_scan_fit``)."""
    apart = estimate.distance_to(carried) > params.drifted_distance or abs(
        float(wrap_angle(estimate.yaw - carried.yaw))
    ) > math.radians(params.drifted_turn)
    if apart and carried_fit >= max(fit + params.keep_rectified_margin, min_scan_fit):
        # A filter that drifted off a good coarse result fits the scan worse than the carried pose.
        return Settlement.KEEP_RECTIFIED
    if fit < min_scan_fit:
        # The cloud settled where only the beams it kept agree (the far side of a wall, say).
        return Settlement.LOST if reseeded else Settlement.RESEED
    return Settlement.ACCEPT


@dataclass(frozen=True)
class FineTuned:
    """Fine tuning's pose and covariance at its last frame."""

    frame: SensorFrame
    pose: Pose2D
    covariance: np.ndarray
    converged: bool  # the covariance fell below the thresholds (not the distance limit, not kept rectified)


@dataclass(frozen=True)
class FineLost:
    """Fine tuning lost the robot: the scans do not fit the map."""

    frame: SensorFrame
    reason: str


@dataclass
class FineTuningHooks:
    """What fine tuning reports back to the session on every control period."""

    record_frame: Callable[[SensorFrame, int], None]  # log the period (frame, step)
    note: Callable[[float, str], None]  # log why the state stays ``fine`` (t, why)
    emit: Callable[[SensorFrame, dict], None]  # the live view's status


def matched_pairs(
    features: list[ConfirmedFeature], matched_ids: list[str | None], bim_features: list[Feature]
) -> tuple[np.ndarray, np.ndarray]:
    """(odom positions, BIM positions) of the confirmed ``features`` the coarse match matched
    (``matched_ids``: the BIM feature of each, None for an outlier)."""
    by_id = {f.id: f for f in bim_features}
    pairs = [
        (f.xy, (by_id[m].x, by_id[m].y)) for f, m in zip(features, matched_ids, strict=False) if m in by_id
    ]
    if not pairs:
        return np.zeros((0, 2)), np.zeros((0, 2))
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs], dtype=float)


class FineTuning:
    """Eq. 18 on one storey's occupancy grid, wall following on ``side`` meanwhile; a pose needs
    ``min_scan_fit`` of the scan on the map (``verification.min_fine_scan_fit``)."""

    def __init__(
        self,
        params: FineTuningSection,
        min_scan_fit: float,
        grid: OccupancyGrid,
        rng: np.random.Generator,
        side: int,
        follow: WallFollowParams,
    ) -> None:
        self.params = params
        self.min_scan_fit = min_scan_fit
        self.grid = grid
        self.rng = rng
        self.side = side
        self.follow = follow

    def run(
        self,
        driver: RobotDriver,
        frame: SensorFrame,
        seed: Pose2D,
        transform: Pose2D,
        landmarks: tuple[np.ndarray, np.ndarray],
        hooks: FineTuningHooks,
    ) -> FineTuned | FineLost:
        """Track from ``frame`` with the filter seeded at ``seed`` and weighted by the matched
        ``landmarks`` (odom, BIM positions); ``transform`` (odom -> BIM) carries the rectified pose."""
        cfg = self.params
        pf = ParticleFilter(likelihood_field(self.grid), cfg.particles, FilterNoise(), LaserModel(), self.rng)
        pf.seed(seed, cfg.seed_sigma_xy, math.radians(cfg.seed_sigma_yaw))
        odom_xy, bim_xy = landmarks
        k = cfg.landmarks
        pf.weight_by_landmarks(frame.odom, odom_xy[-k:], bim_xy[-k:], cfg.landmark_sigma)
        start_distance = driver.distance
        reseeded = False
        last_update = frame.odom
        lost = 0
        step = 0
        converged_at: float | None = None
        while True:
            view = (
                ScanView.of(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
                if frame.scan
                else None
            )
            v, w = wall_follow(view, self.side, self.follow) if view is not None else (0.0, 0.0)
            frame = driver.step(v, w)
            step += 1
            hooks.record_frame(frame, step)
            scan = frame.scan
            if scan is None:
                continue  # nothing to update the filter with; its motion update waits for a scan
            moved = motion_delta(last_update, frame.odom)
            if abs(moved[1]) < cfg.update_min_d and abs(moved[0] + moved[2]) < cfg.update_min_a:
                continue
            pf.predict(moved)
            last_update = frame.odom
            pf.update(scan.angles, scan.ranges, scan.range_max)
            lost = lost + 1 if pf.last_likelihood < cfg.lost_likelihood else 0
            estimate = pf.estimate()
            cov = estimate.covariance
            hooks.emit(frame, {"covariance": float(max(cov[0, 0], cov[1, 1]))})
            if lost >= cfg.lost_updates:
                return FineLost(frame, "lost during fine tuning (laser scans do not fit the map)")
            travelled = driver.distance - start_distance
            if (
                cov[0, 0] < cfg.covariance
                and cov[1, 1] < cfg.covariance
                and cov[2, 2] < cfg.yaw_covariance
                and travelled >= cfg.min_travel
            ):
                converged_at = frame.t
            if converged_at is None and travelled < cfg.distance:
                continue
            fit = scan_fit(estimate.pose, scan.angles, scan.ranges, scan.range_max, pf.field)
            carried = transform * frame.odom
            carried_fit = scan_fit(carried, scan.angles, scan.ranges, scan.range_max, pf.field)
            verdict = settle(estimate.pose, fit, carried, carried_fit, reseeded, cfg, self.min_scan_fit)
            if verdict is Settlement.KEEP_RECTIFIED:
                hooks.note(
                    frame.t, f"filter drifted (scan fit {fit:.0%}); rectified pose kept ({carried_fit:.0%})"
                )
                sent = self.covariance(cov, estimate.pose, carried, carried, scan, pf.field)
                return FineTuned(frame, carried, sent, converged=False)
            if verdict is Settlement.LOST:
                return FineLost(frame, f"lost during fine tuning (only {fit:.0%} of the scan fits the map)")
            if verdict is Settlement.RESEED:
                # Spread the cloud wider around the estimate and track again.
                reseeded = True
                hooks.note(frame.t, f"scan fit {fit:.0%}, reseeded")
                pf.seed(estimate.pose, cfg.reseed_sigma_xy, math.radians(cfg.seed_sigma_yaw))
                start_distance, converged_at = driver.distance, None
                continue
            sent = self.covariance(cov, estimate.pose, carried, estimate.pose, scan, pf.field)
            return FineTuned(frame, estimate.pose, sent, converged=converged_at is not None)

    def covariance(
        self,
        cloud: np.ndarray,
        estimate: Pose2D,
        carried: Pose2D,
        sent: Pose2D,
        scan: LaserScan,
        field: LikelihoodField,
    ) -> np.ndarray:
        """What is sent with the ``sent`` pose (the filter's ``estimate`` or the ``carried`` claim):
        the ``cloud``'s covariance and what the cloud cannot see (their disagreement, how much the
        pose rests on one part of the last ``scan``)."""
        cfg = self.params
        jack = sector_jackknife(sent, scan.angles, scan.ranges, scan.range_max, field)
        return honest_covariance(
            cloud, estimate, carried, cfg.covariance_floor_m, cfg.covariance_floor_deg, jack
        )


class FineStage:
    """The fine stage after each claim: fine tuning on the claimed storey's grid (``fine_tuning``
    enabled), and the stages that failed (the ``fine_tuning.tries``-th ends the session)."""

    def __init__(
        self,
        params: FineTuningSection,
        min_scan_fit: float,
        rng: np.random.Generator,
        follow: WallFollowParams,
    ) -> None:
        self.params = params
        self.min_scan_fit = min_scan_fit  # verification.min_fine_scan_fit
        self.rng = rng
        self.follow = follow
        self.failures = 0  # fine stages that failed
        self.failed_why = ""  # why the last one failed

    def tunes(self, model: StoreyModel) -> bool:
        """Does the fine stage on ``model`` run the filter (else the coarse pose is carried on)?"""
        return self.params.enabled and model.grid is not None

    def run(
        self,
        driver: RobotDriver,
        frame: SensorFrame,
        model: StoreyModel,
        transform: Pose2D,
        side: int,
        result: SessionResult,
        hooks: FineTuningHooks,
    ) -> FineTuned | FineLost:
        """Fine-tune the claim of ``result`` (odom -> BIM ``transform``) on ``model``'s grid, seeded at
        the rectified pose and weighted by its matched features, following the wall on ``side``."""
        assert model.grid is not None
        tuning = FineTuning(self.params, self.min_scan_fit, model.grid, self.rng, side, self.follow)
        landmarks = matched_pairs(result.features, result.matched_ids, model.features)
        return tuning.run(driver, frame, transform * frame.odom, transform, landmarks, hooks)

    def failed(self, reason: str) -> bool:
        """A fine stage failed for ``reason``: was it the last try?"""
        self.failures += 1
        self.failed_why = reason
        return self.failures >= self.params.tries

    @property
    def earlier_failure(self) -> str:
        """Why the last fine stage failed ("" if none did)."""
        return self.failed_why if self.failures else ""
