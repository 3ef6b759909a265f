"""Robustness sweeps (``--sweep KEY=V1,V2,...``): one session parameter varied, the rest fixed."""

from __future__ import annotations

import copy
import dataclasses
import json
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from bimkit.checks import check_number
from bimkit.errors import InputError
from initcli.config import SCHEMA_PATH as SITE_SCHEMA
from initcli.config import SessionConfig
from initcli.config.checks import problems

__all__ = ["SWEEP_KEYS", "Sweep", "apply_sweep", "check_sweep", "format_value", "parse_sweep", "sweep_label"]

# Short names for the parameters the issue asks to sweep; any dotted config path works too.
SWEEP_KEYS: dict[str, str] = {
    "miss_rate": "sim.miss_rate",  # chance a visible feature is not detected in an image (0-1)
    "false_positives": "sim.false_positives_per_minute",
    "depth_noise": "camera.depth_noise",  # sigma = depth_noise * d^2
    "odometry_drift": "sim.odometry_noise",  # a factor on all four odometry alphas (1 = as configured)
    "clutter": "sim.clutter",  # material stacks per metre of corridor wall
    "people": "sim.people",  # people walking about (not the --workers processes)
    "phantoms": "sim.phantoms",
    "alpha": "matching.alpha",  # m, Eq. 7
    "beta": "matching.beta",  # degrees, Eq. 9
}

# Earlier names still read: sim.workers became sim.people (it never meant CPU workers).
OLD_SWEEP_KEYS: dict[str, str] = {"workers": "sim.people", "sim.workers": "sim.people"}


@dataclass(frozen=True)
class Sweep:
    key: str  # as the user wrote it
    path: str  # dotted path in the session config
    values: tuple[float, ...]

    def labels(self) -> list[str]:
        return [format_value(v) for v in self.values]


def format_value(value: float) -> str:
    return f"{value:g}"


def sweep_label(sweep: Sweep | None, value: float | None) -> tuple[str, str]:
    """(key, value) a trial record carries; ("", "") outside a sweep."""
    if sweep is None or value is None:
        return "", ""
    return sweep.key, format_value(value)


def _resolve(config: SessionConfig, path: str) -> tuple[object, str]:
    """(the dataclass holding the field, the field name) of a dotted path; raises ``KeyError``."""
    parts = path.split(".")
    node: object = config
    for part in parts[:-1]:
        if not dataclasses.is_dataclass(node) or part not in {f.name for f in dataclasses.fields(node)}:
            raise KeyError(path)
        node = getattr(node, part)
    if not dataclasses.is_dataclass(node) or parts[-1] not in {f.name for f in dataclasses.fields(node)}:
        raise KeyError(path)
    return node, parts[-1]


def parse_sweep(text: str, config: SessionConfig | None = None) -> Sweep:
    """``KEY=V1,V2,...`` with KEY one of :data:`SWEEP_KEYS` or a dotted numeric config path."""
    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise InputError(f"--sweep: expected KEY=V1,V2,... (e.g. miss_rate=0,0.25,0.5), got {text!r}")
    path = SWEEP_KEYS.get(key) or OLD_SWEEP_KEYS.get(key, key)
    try:
        numbers = tuple(float(v) for v in values.split(",") if v.strip())
    except ValueError:
        raise InputError(f"--sweep {key}: values must be numbers, got {values!r}") from None
    if not numbers:
        raise InputError(f"--sweep {key}: no values given")
    probe = config or SessionConfig()
    try:
        node, name = _resolve(probe, path)
    except KeyError:
        known = ", ".join(SWEEP_KEYS)
        raise InputError(
            f"--sweep: unknown key {key!r} (one of {known}, or a dotted site-config path)"
        ) from None
    current = getattr(node, name)
    if not (dataclasses.is_dataclass(current) or isinstance(current, int | float)) or isinstance(
        current, bool
    ):
        raise InputError(f"--sweep {key}: {path} is not a number")
    if dataclasses.is_dataclass(current):
        whole = [
            f.name for f in dataclasses.fields(current) if not isinstance(getattr(current, f.name), float)
        ]
        if whole:  # counts, switches, names: a factor on them is no setting
            raise InputError(
                f"--sweep {key}: {path} is a section whose settings do not all scale ({', '.join(whole[:3])} "
                f"...); sweep one of its numbers, e.g. {path}.{_first_float(current) or 'KEY'}"
            )
    for value in numbers:
        _check_value(key, path, value, scaled=dataclasses.is_dataclass(current))
    return Sweep(key, path, numbers)


def _first_float(section: Any) -> str | None:
    fields = dataclasses.fields(section)
    return next((f.name for f in fields if isinstance(getattr(section, f.name), float)), None)


def _field_schema(path: str) -> dict:
    """The site-config schema of the field at a dotted path (its range)."""
    node: dict = json.loads(SITE_SCHEMA.read_text(encoding="utf-8"))
    for part in path.split("."):
        node = node.get("properties", {}).get(part, {})
    return node


def _check_value(key: str, path: str, value: float, scaled: bool) -> None:
    """A swept value is finite and within the field's range in the site-config schema; a factor
    on a section (``odometry_drift``) is within [0, 1000]."""
    name = f"--sweep {key}"
    if scaled:
        check_number(value, name, minimum=0, maximum=1000)
        return
    schema = _field_schema(path)
    bounds = {
        "minimum": schema.get("minimum"),
        "maximum": schema.get("maximum"),
        "above": schema.get("exclusiveMinimum"),
        "below": schema.get("exclusiveMaximum"),
    }
    check_number(value, name, **bounds)
    if schema.get("type") == "integer" and not value.is_integer():
        raise InputError(f"{name}: {path} takes whole numbers, got {value:g}")


def apply_sweep(config: SessionConfig, sweep: Sweep, value: float) -> SessionConfig:
    """A copy of ``config`` with the swept parameter set to ``value``.

    A section (``sim.odometry_noise``) is scaled: every number in it is multiplied by ``value``.
    """
    out = copy.deepcopy(config)
    node, name = _resolve(out, sweep.path)
    current = getattr(node, name)
    if dataclasses.is_dataclass(current) and not isinstance(current, type):
        scaled = {
            f.name: getattr(current, f.name) * value
            for f in dataclasses.fields(current)
            if isinstance(getattr(current, f.name), int | float)
        }
        setattr(node, name, dataclasses.replace(current, **scaled))
    else:
        setattr(node, name, type(current)(value) if isinstance(current, int) else float(value))
    return out


def check_sweep(sweep: Sweep, configs: Iterable[SessionConfig]) -> None:
    """Every swept value passes the site config's cross-field checks (:mod:`initcli.config.checks`)
    on every site: ``matching.min_depth`` swept above ``matching.max_depth``, ``miss_rate`` swept in
    a config that has a detector profile, ... are refused before any trial runs."""
    for config in configs:
        for value in sweep.values:
            for problem in problems(apply_sweep(config, sweep, value), {sweep.path}):
                where = f" ({config.source})" if config.source else ""
                raise InputError(f"--sweep {sweep.key}={format_value(value)}{where}: {problem}")
