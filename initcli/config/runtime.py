"""The session config turned into what the algorithms take: the camera, the wall follower's and the
matcher's parameters, the simulated world's deviations."""

from __future__ import annotations

import dataclasses
import math

from initcli.config.exploration import WallSide
from initcli.config.matching import MatchingSettings, MatchOptions
from initcli.config.session import SessionConfig
from initcli.config.sim import AsBuiltParams, PersistentDetectorErrors
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.navigation.wall_following import WallFollowParams

__all__ = [
    "as_built_params",
    "camera_of",
    "followed_side",
    "match_options",
    "start_pose_degrees",
    "turn_in_place_speed",
    "wall_follow_params",
]


def as_built_params(config: SessionConfig) -> AsBuiltParams:
    """The simulated world's deviations from the design (sim.as_built + sim.detector)."""
    persistent = {
        f.name: getattr(config.sim.detector, f.name) for f in dataclasses.fields(PersistentDetectorErrors)
    }
    return AsBuiltParams(**dataclasses.asdict(config.sim.as_built), **persistent)


def start_pose_degrees(config: SessionConfig) -> tuple[float, float, float] | None:
    if config.sim.start == "random":
        return None
    x, y, yaw = config.sim.start
    return float(x), float(y), math.radians(float(yaw))


def match_options(config: SessionConfig, storey: str | None) -> MatchOptions:
    """The session's matching options: the ``matching:`` section's share of them, with
    ``detector.score_threshold`` and ``exploration.d_thre``; enough hypotheses are kept to decide on
    active exploration (``m_thre``)."""
    m = config.matching
    shared = {f.name: getattr(m, f.name) for f in dataclasses.fields(MatchingSettings)}
    return MatchOptions(
        **shared,
        storey=storey,
        top=max(m.m_thre, MatchOptions.top),
        d_thre=config.exploration.d_thre,
        score_threshold=config.detector.score_threshold,
        registration=config.registration.enabled,
    )


def followed_side(config: SessionConfig) -> int:
    """+1: follow the left wall, -1: the right one (random exploration, §3.3.4)."""
    return 1 if config.exploration.wall_side == WallSide.LEFT else -1


def wall_follow_params(config: SessionConfig) -> WallFollowParams:
    """The wall follower's settings from the robot and exploration sections."""
    return WallFollowParams(
        distance=config.exploration.wall_distance,
        speed=config.robot.max_linear,
        max_turn=config.robot.max_angular,
        front_stop=config.robot.radius + config.exploration.front_clearance,
        radius=config.robot.radius,
    )


def turn_in_place_speed(config: SessionConfig) -> float:
    """rad/s of the look round at the start and of the recovery rotation (§3.3.4)."""
    return config.exploration.turn_rate * config.robot.max_angular


def camera_of(config: SessionConfig) -> tuple[CameraIntrinsics, CameraMount]:
    """The camera's intrinsics and its mount on the robot (``camera:``)."""
    c = config.camera
    intrinsics = CameraIntrinsics(c.fx, c.fy, c.cx, c.cy, int(c.width), int(c.height))
    p = c.pose
    return intrinsics, CameraMount(p.x, p.y, p.z, p.roll, p.pitch, p.yaw)
