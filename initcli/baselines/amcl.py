"""The ``amcl`` baseline (§4.3): AMCL global localisation while following the wall.

"The AMCL global localization mode was tested for the robot initialization by generating 5000
randomly distributed particles on the map [...] the localization was considered completed when
the covariance was lower than the predefined threshold. The selected threshold was the same as
that for PF-based fine tuning" (§4.3). The robot explores exactly as ``bim-init run`` does
(:class:`~initcli.baselines.drive.WallFollowingExplorer`) and the filter is driven the way
fine tuning drives its tracking filter (Eq. 18): an update after ``update_min_d`` /
``update_min_a`` of odometry motion. The attempt gives up after ``limits.max_distance`` (150 m,
the paper's failure rule) or ``limits.max_time``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bimtools.site.load import Site
from initcli.baselines.drive import drive_attempts, limit_passed
from initcli.baselines.outcome import LocalisationOutcome
from initcli.config import SessionConfig
from initcli.core.filters.global_localisation import GlobalLocalisation, GlobalLocalisationParams
from initcli.core.geometry.motion import motion_delta
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import SensorFrame
from initcli.sim.build import SimSetup

__all__ = ["AmclAttempt", "AmclTracePoint", "MIN_TRAVEL", "converged", "run_amcl"]

MIN_TRAVEL = 1.0  # m driven before a convergence claim counts (as in fine tuning)


@dataclass(frozen=True)
class AmclTracePoint:
    """One filter update: simulated time, distance driven, particles kept, whole-set x/y variance."""

    t: float
    distance_m: float
    particles: int
    variance_xy: float


def converged(covariance: np.ndarray, config: SessionConfig) -> bool:
    """The fine-tuning thresholds (§3.3.5): x and y variances and the yaw variance."""
    cfg = config.fine_tuning
    return (
        covariance[0, 0] < cfg.covariance
        and covariance[1, 1] < cfg.covariance
        and covariance[2, 2] < cfg.yaw_covariance
    )


class AmclAttempt:
    """AMCL in global localisation mode along the wall-following drive (a
    :class:`~initcli.baselines.drive.BaselineAttempt`)."""

    def __init__(
        self,
        config: SessionConfig,
        site: Site,
        setup: SimSetup,
        rng: np.random.Generator,
        params: GlobalLocalisationParams | None = None,
        trace: list[AmclTracePoint] | None = None,
    ) -> None:
        grid = site.storeys[setup.storey].grid
        if grid is None:
            raise ValueError(f"storey {setup.storey!r} has no occupancy grid")
        self.config = config
        self.amcl = GlobalLocalisation(
            grid, params if params is not None else GlobalLocalisationParams(), rng
        )
        self.driver = setup.driver
        self.trace = trace
        self.last_update: Pose2D | None = None

    def _outcome(
        self, frame: SensorFrame, localised: bool, reason: str, pose: Pose2D | None = None
    ) -> LocalisationOutcome:
        return LocalisationOutcome(
            method="amcl",
            localised=localised,
            reason=reason,
            pose=pose,
            truth=frame.truth,
            distance_m=round(self.driver.distance, 3),
            duration_s=round(frame.t, 2),
            features=0,
        )

    def start(self, frame: SensorFrame) -> LocalisationOutcome | None:
        if frame.scan is not None:  # ROS AMCL integrates the first scan before any motion
            self.amcl.update(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
        self.last_update = frame.odom
        return None

    def observe(self, frame: SensorFrame, step: int) -> LocalisationOutcome | None:
        passed = limit_passed(self.config, self.driver.distance, frame.t)
        if passed is not None:
            return self._outcome(frame, False, f"not converged after {passed}")
        assert self.last_update is not None
        moved = motion_delta(self.last_update, frame.odom)
        amcl = self.amcl
        if frame.scan is None or not amcl.moved_enough(moved):
            return None
        amcl.predict(moved)
        amcl.update(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
        self.last_update = frame.odom
        covariance = amcl.whole_covariance()
        distance = self.driver.distance
        if self.trace is not None:
            self.trace.append(
                AmclTracePoint(frame.t, distance, amcl.count, float(max(covariance[0, 0], covariance[1, 1])))
            )
        if distance >= MIN_TRAVEL and converged(covariance, self.config):
            estimate = amcl.estimate()
            return self._outcome(
                frame, True, "converged (covariance below the fine-tuning thresholds)", estimate.pose
            )
        return None


def run_amcl(
    config: SessionConfig,
    site: Site,
    setup: SimSetup,
    rng: np.random.Generator,
    params: GlobalLocalisationParams | None = None,
    *,
    trace: list[AmclTracePoint] | None = None,
) -> LocalisationOutcome:
    """Follow the wall with AMCL in global localisation mode until it converges or gives up.

    ``trace``, when given, receives one :class:`AmclTracePoint` per filter update.
    """
    return drive_attempts(config, setup.driver, [AmclAttempt(config, site, setup, rng, params, trace)])[0]
