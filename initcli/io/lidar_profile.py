"""A lidar profile: what a real 2D lidar sees that the BIM does not, measured on real laser logs
(``benchmarks/measure_lidar_profile.py``) and applied by the simulator (``lidar.profile``,
:func:`initcli.sim.build.build_sim`).

A profile sets three things of the simulated world and lidar, in place of the config's own: the
range noise (``lidar.noise``, m), the share of beams with no return (``lidar.dropout``) and the
material stacks per metre of corridor wall (``sim.clutter``) at which the simulated scans' share
of beams ending off the BIM's walls comes nearest the real one. The rest of the file (the
measurements per log and pooled, the odometry drift the logs cannot show, the provenance) is
record only. It imports nothing of the config or the simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bimkit.documents import read_json
from bimkit.errors import InputError

__all__ = [
    "LIDAR_PROFILE_FORMAT",
    "LIDAR_PROFILE_NAMES",
    "LidarProfile",
    "read_lidar_profile",
    "resolve_lidar_profile",
]

LIDAR_PROFILE_FORMAT = "bim-init.lidar-profile/1"
PROFILES_DIR = Path(__file__).resolve().parent.parent / "sim" / "profiles"
# The profiles shipped in the package (benchmarks/measure_lidar_profile.py --write measures them).
LIDAR_PROFILE_NAMES: dict[str, Path] = {"real-logs": PROFILES_DIR / "lidar_real_logs.json"}
# What a profile sets: (its key under "sim", the config key it replaces, lowest, highest).
SETS = (
    ("noise", "lidar.noise", 0.0, 5.0),
    ("dropout", "lidar.dropout", 0.0, 1.0),
    ("clutter", "sim.clutter", 0.0, 10.0),
)
LIDAR_PROFILE_REPLACES = tuple(key for _, key, _, _ in SETS)


@dataclass(frozen=True)
class LidarProfile:
    """The simulator's settings a profile replaces (see the module's docstring)."""

    name: str
    noise: float  # m: range noise sd (lidar.noise)
    dropout: float  # share of beams with no return (lidar.dropout)
    clutter: float  # material stacks per metre of corridor wall (sim.clutter)

    @staticmethod
    def from_dict(doc: Any, where: str) -> LidarProfile:
        if not isinstance(doc, dict) or doc.get("format") != LIDAR_PROFILE_FORMAT:
            raise InputError(f"{where}: not a lidar profile (format {LIDAR_PROFILE_FORMAT!r} expected)")
        sim = doc.get("sim")
        if not isinstance(sim, dict):
            raise InputError(f"{where}: sim: an object of {', '.join(k for k, _, _, _ in SETS)} expected")
        values = {}
        for key, _, low, high in SETS:
            value = sim.get(key)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InputError(f"{where}: sim.{key}: a number expected")
            if not low <= value <= high:
                raise InputError(f"{where}: sim.{key}: {value} is outside {low:g} to {high:g}")
            values[key] = float(value)
        return LidarProfile(str(doc.get("name", "")), **values)


def resolve_lidar_profile(name: str, base: Path | None = None) -> Path:
    """``real-logs`` -> the shipped profile; anything else a path (relative to ``base``, the folder
    of the config that names it)."""
    key = name.strip().lower()
    if key in LIDAR_PROFILE_NAMES:
        return LIDAR_PROFILE_NAMES[key]
    path = Path(name).expanduser()
    return path if path.is_absolute() or base is None else base / path


def read_lidar_profile(path: Path) -> LidarProfile:
    """The profile at ``path``; a missing, unreadable or malformed file is one :class:`InputError`."""
    path = Path(path)
    if not path.exists():
        raise InputError(
            f"{path}: no such lidar profile (benchmarks/measure_lidar_profile.py writes one; shipped:"
            f" {', '.join(LIDAR_PROFILE_NAMES)})"
        )
    return LidarProfile.from_dict(read_json(path, "a lidar profile (JSON)"), str(path))
