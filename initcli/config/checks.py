"""Cross-field checks of the session config: settings each within its own range (the schema's
bounds, :mod:`bimkit.settings`) that contradict one another or make no physical sense together.

Run by :func:`initcli.config.parse_config` when a config is loaded, after the schema: the first
problem is one :class:`~bimkit.errors.InputError` naming the YAML paths it compares. Each check is a
small function of the config and the dotted paths the file itself sets (``given``); :data:`CHECKS`
lists them in the order they run.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from bimkit.checks import show_number
from bimkit.errors import InputError
from initcli.config.session import SessionConfig
from initcli.config.sim import PROFILE_REPLACES
from initcli.detector import RUNTIME_AVAILABLE, RUNTIME_MISSING
from initcli.detector.profile import DetectorProfile, read_profile, resolve_profile
from initcli.io.lidar_profile import (
    LIDAR_PROFILE_REPLACES,
    LidarProfile,
    read_lidar_profile,
    resolve_lidar_profile,
)

__all__ = [
    "CHECKS",
    "check_config",
    "detector_profile",
    "given_paths",
    "lidar_profile",
    "problems",
    "profile_path",
]

Check = Callable[[SessionConfig, set[str]], str | None]


def given_paths(doc: Any, prefix: str = "") -> set[str]:
    """Every dotted path a config document sets (``camera.fx``, ``sim.detector.profile``)."""
    out: set[str] = set()
    if isinstance(doc, dict):
        for key, value in doc.items():
            path = f"{prefix}{key}"
            out.add(path)
            out |= given_paths(value, f"{path}.")
    return out


def profile_path(config: SessionConfig) -> Path | None:
    """The file ``sim.detector.profile`` names (a shipped profile's, or relative to the config's
    folder), or None."""
    name = config.sim.detector.profile
    return resolve_profile(name, config.source.parent if config.source else None) if name else None


def detector_profile(config: SessionConfig) -> DetectorProfile | None:
    """The measured profile the simulated detector draws from (``sim.detector.profile``), or None."""
    path = profile_path(config)
    return None if path is None else read_profile(path)


def lidar_profile(config: SessionConfig) -> LidarProfile | None:
    """The measured lidar profile the simulator takes its lidar noise, dropout and clutter from
    (``lidar.profile``: a shipped profile's name, or a file relative to the config's folder), or None."""
    name = config.lidar.profile
    if not name:
        return None
    return read_lidar_profile(resolve_lidar_profile(name, config.source.parent if config.source else None))


def _n(value: float) -> str:
    return show_number(value)


def depth_limits(c: SessionConfig, given: set[str]) -> str | None:
    m = c.matching
    if m.min_depth >= m.max_depth:
        return (
            f"matching.min_depth ({_n(m.min_depth)} m) must be below matching.max_depth"
            f" ({_n(m.max_depth)} m): every detection would be ignored"
        )
    return None


def principal_point(c: SessionConfig, given: set[str]) -> str | None:
    cam = c.camera
    for axis, size, name in ((cam.cx, cam.width, "width"), (cam.cy, cam.height, "height")):
        key = "cx" if name == "width" else "cy"
        if not 0 <= axis <= size:
            return (
                f"camera.{key} ({_n(axis)} px) lies outside the image (camera.{name} {size} px): the"
                " principal point must be within it"
            )
    return None


def camera_ranges(c: SessionConfig, given: set[str]) -> str | None:
    cam = c.camera
    if cam.min_range >= cam.range:
        return (
            f"camera.min_range ({_n(cam.min_range)} m) must be below camera.range ({_n(cam.range)} m):"
            " the camera would read no depth at all"
        )
    return None


def miss_odds(c: SessionConfig, given: set[str]) -> str | None:
    v = c.verification
    if v.p_right > v.p_wrong:
        return (
            f"verification.p_right ({_n(v.p_right)}) is above verification.p_wrong ({_n(v.p_wrong)}): a"
            " feature missed would count for the place instead of against it"
        )
    return None


def wall_distance(c: SessionConfig, given: set[str]) -> str | None:
    if c.exploration.wall_distance <= c.robot.radius:
        return (
            f"exploration.wall_distance ({_n(c.exploration.wall_distance)} m) must be above robot.radius"
            f" ({_n(c.robot.radius)} m): the robot would follow the wall inside it"
        )
    return None


def fine_travel(c: SessionConfig, given: set[str]) -> str | None:
    f = c.fine_tuning
    if f.enabled and f.min_travel > f.distance:
        return (
            f"fine_tuning.min_travel ({_n(f.min_travel)} m) is above fine_tuning.distance"
            f" ({_n(f.distance)} m): the filter could never count as converged"
        )
    return None


def profile_or_rates(c: SessionConfig, given: set[str]) -> str | None:
    if not c.sim.detector.profile:
        return None
    both = [f"sim.{k}" for k in PROFILE_REPLACES if f"sim.{k}" in given]
    if both:
        return (
            f"sim.detector.profile replaces {', '.join(both)}: set the profile or the flat"
            f" rate{'s' if len(both) > 1 else ''}, not both"
        )
    if c.detector.kind != "simulated":
        return (
            f"sim.detector.profile is for detector.kind simulated (detector.kind {c.detector.kind} runs"
            " the network itself)"
        )
    return None


def detector_runtime(c: SessionConfig, given: set[str]) -> str | None:
    if c.detector.kind == "onnx" and not RUNTIME_AVAILABLE:
        return f"detector.kind onnx {RUNTIME_MISSING}"
    return None


def profile_file(c: SessionConfig, given: set[str]) -> str | None:
    if not c.sim.detector.profile:
        return None
    try:
        detector_profile(c)
    except InputError as exc:
        return f"sim.detector.profile: {exc}"
    return None


def lidar_profile_or_values(c: SessionConfig, given: set[str]) -> str | None:
    if not c.lidar.profile:
        return None
    both = [k for k in LIDAR_PROFILE_REPLACES if k in given]
    if both:
        return (
            f"lidar.profile replaces {', '.join(both)}: set the profile or the value"
            f"{'s' if len(both) > 1 else ''}, not both"
        )
    try:
        lidar_profile(c)
    except InputError as exc:
        return f"lidar.profile: {exc}"
    return None


CHECKS: tuple[Check, ...] = (
    depth_limits,
    principal_point,
    camera_ranges,
    miss_odds,
    wall_distance,
    fine_travel,
    profile_or_rates,
    detector_runtime,
    profile_file,
    lidar_profile_or_values,
)


def problems(config: SessionConfig, given: set[str]) -> Iterator[str]:
    for check in CHECKS:
        problem = check(config, given)
        if problem:
            yield problem


def check_config(config: SessionConfig, given: set[str], where: str) -> None:
    """The first cross-field problem of ``config`` as one :class:`InputError` (``where``: the file)."""
    for problem in problems(config, given):
        raise InputError(f"{where}: {problem}")
