"""A differential-drive robot: true motion in the world, and wheel odometry that drifts.

Odometry noise follows the odometry motion model of probabilistic robotics / AMCL (rot1, trans,
rot2), with variances that grow linearly with the motion of each step, so the drift does not
depend on the control rate:

    var(rot)   = alpha1 * |d_rot|   + alpha2 * |d_trans|     (rad^2)
    var(trans) = alpha3 * |d_trans| + alpha4 * |d_rot|       (m^2)

On top of that random walk, a real base has systematic errors: ``scale_error`` (a wheel radius 2 %
off makes odometry count 2 % too far: ``0.02``) and wheel *slip* events (``slip_per_100m``), where
odometry counts 5-30 cm the robot did not drive and turns by a few degrees it did not turn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from initcli.core.geometry.motion import apply_delta, motion_delta
from initcli.core.geometry.se2 import Pose2D, wrap_angle

__all__ = ["DiffDriveRobot", "OdometryNoise"]


@dataclass(frozen=True)
class OdometryNoise:
    alpha1: float = 0.0001  # rad^2 per rad turned (a 90 degree turn: sigma 0.7 degrees)
    alpha2: float = 0.00001  # rad^2 per metre driven (50 m: sigma 1.3 degrees)
    alpha3: float = 0.0004  # m^2 per metre driven
    alpha4: float = 0.0001  # m^2 per rad turned
    scale_error: float = 0.0  # systematic share of translation counted too far (0.02: 2 %)
    slip_per_100m: float = 0.0  # wheel-slip events per 100 m driven

    def scaled(self, factor: float) -> OdometryNoise:
        """The random walk ``factor`` times stronger; the systematic errors unchanged."""
        return replace(
            self,
            alpha1=self.alpha1 * factor,
            alpha2=self.alpha2 * factor,
            alpha3=self.alpha3 * factor,
            alpha4=self.alpha4 * factor,
        )


class DiffDriveRobot:
    """True pose in the BIM frame, odometry pose in the odom frame (origin = start pose)."""

    def __init__(self, start: Pose2D, radius: float, noise: OdometryNoise, rng: np.random.Generator):
        self.pose = start
        self.odom = Pose2D.identity()
        self.radius = radius
        self.noise = noise
        self.rng = rng
        self.distance = 0.0
        self.collisions = 0
        self.slips = 0
        self._next_slip = self._slip_gap()

    def _slip_gap(self) -> float:
        """Metres to the next slip event (exponential); the generator is untouched without slips."""
        rate = self.noise.slip_per_100m
        return math.inf if rate <= 0 else self.distance + float(self.rng.exponential(100.0 / rate))

    def proposed(self, v: float, w: float, dt: float) -> Pose2D:
        """Where the commands (v, w) would take the robot in ``dt`` (exact arc)."""
        p = self.pose
        if abs(w) < 1e-9:
            return Pose2D(p.x + v * dt * math.cos(p.yaw), p.y + v * dt * math.sin(p.yaw), p.yaw)
        yaw = p.yaw + w * dt
        r = v / w
        return Pose2D(
            p.x + r * (math.sin(yaw) - math.sin(p.yaw)),
            p.y - r * (math.cos(yaw) - math.cos(p.yaw)),
            float(wrap_angle(yaw)),
        )

    def move_to(self, new: Pose2D) -> None:
        """Move to ``new`` and integrate the noisy odometry of that motion."""
        rot1, trans, rot2 = motion_delta(self.pose, new)
        n = self.noise
        s_rot1 = math.sqrt(n.alpha1 * abs(rot1) + n.alpha2 * abs(trans))
        s_trans = math.sqrt(n.alpha3 * abs(trans) + n.alpha4 * (abs(rot1) + abs(rot2)))
        s_rot2 = math.sqrt(n.alpha1 * abs(rot2) + n.alpha2 * abs(trans))
        measured = (
            rot1 + self.rng.normal(0.0, s_rot1) if s_rot1 > 0 else rot1,
            trans + self.rng.normal(0.0, s_trans) if s_trans > 0 else trans,
            rot2 + self.rng.normal(0.0, s_rot2) if s_rot2 > 0 else rot2,
        )
        if n.scale_error:
            measured = (measured[0], measured[1] * (1.0 + n.scale_error), measured[2])
        self.distance += abs(trans)
        if self.distance >= self._next_slip:
            # The wheels spun: odometry counts ground and a turn that the robot did not make.
            extra = math.copysign(float(self.rng.uniform(0.05, 0.3)), trans if trans else 1.0)
            turn = float(self.rng.normal(0.0, math.radians(2.0)))
            measured = (measured[0], measured[1] + extra, measured[2] + turn)
            self.slips += 1
            self._next_slip = self._slip_gap()
        self.odom = apply_delta(self.odom, *measured)
        self.pose = new
