"""The session config (``site.yaml``): sections, documented defaults, validation.

Validated against ``schemas/site_config.schema.json`` before anything runs; an error names the
YAML path and the problem (``camera.fx: expected a number, got "abc"``).
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import sys
from pathlib import Path
from typing import Any

import jsonschema

from bimkit import checks
from bimkit.checks import check_finite_tree, range_problem
from bimkit.errors import InputError
from bimkit.schemas import schema_path
from initcli.config_checks import check_config, given_paths
from initcli.core.particle_filter import LaserModel
from initcli.core.projection import CameraIntrinsics, CameraMount
from initcli.core.wall_following import WallFollowParams
from initcli.match.options import MatchingSettings, MatchOptions
from initcli.settings import schema_of
from initcli.settings_session import (
    CameraPose,
    CameraSection,
    ConfirmSection,
    DetectorSection,
    ExplorationSection,
    FineTuningSection,
    LidarSection,
    LimitsSection,
    MatchingSection,
    Nav2Section,
    RobotSection,
    RosbridgeSection,
    SessionConfig,
    SiteSection,
    VerificationSection,
)
from initcli.settings_sim import (
    REALITY_PROFILES,
    AsBuiltParams,
    AsBuiltSection,
    OdometryNoiseSection,
    PersistentDetectorErrors,
    SimDetectorSection,
    SimOdometrySection,
    SimSection,
)

__all__ = [
    "REALITY_PROFILES",
    "SCHEMA_PATH",
    "AsBuiltSection",
    "CameraPose",
    "CameraSection",
    "ConfirmSection",
    "DetectorSection",
    "ExplorationSection",
    "FineTuningSection",
    "LidarSection",
    "LimitsSection",
    "MatchingSection",
    "Nav2Section",
    "OdometryNoiseSection",
    "RobotSection",
    "RosbridgeSection",
    "SessionConfig",
    "SimDetectorSection",
    "SimOdometrySection",
    "SimSection",
    "SiteSection",
    "VerificationSection",
    "as_built_params",
    "camera_of",
    "check_resources",
    "config_to_dict",
    "followed_side",
    "load_config",
    "match_options",
    "parse_config",
    "read_yaml",
    "site_config_schema",
    "start_pose_degrees",
    "turn_in_place_speed",
    "validate_document",
    "wall_follow_params",
    "with_reality",
]

SCHEMA_PATH = schema_path("site_config.schema.json")
SCHEMA_ID = "https://bim-init.example/schemas/site_config.schema.json"


def site_config_schema() -> dict[str, Any]:
    """The JSON Schema of site.yaml, generated from the records (``python -m initcli.config
    --write`` writes it to :data:`SCHEMA_PATH`; a test fails when the committed file differs)."""
    body = schema_of(SessionConfig)
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": "bim-init run session config (site.yaml)",
        **body,
    }


def _describe(value: Any) -> str:
    if isinstance(value, str):
        return json.dumps(value)
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    return repr(value)


_TYPE_WORDS = {
    "number": "a number",
    "integer": "an integer",
    "string": "a string",
    "boolean": "true or false",
    "object": "a mapping",
    "array": "a list",
    "null": "null",
}


def _message(error: jsonschema.ValidationError) -> tuple[str, str]:
    path = ".".join(str(p) for p in error.absolute_path)
    v = error.validator
    if v == "type":
        types = error.validator_value if isinstance(error.validator_value, list) else [error.validator_value]
        want = " or ".join(_TYPE_WORDS.get(str(t), str(t)) for t in types)
        return path, f"expected {want}, got {_describe(error.instance)}"
    if v == "enum":
        return (
            path,
            f"expected one of {', '.join(map(str, error.validator_value))}, got {_describe(error.instance)}",
        )
    if v in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
        bound = {"minimum": "minimum", "exclusiveMinimum": "above", "maximum": "maximum"}.get(v, "below")
        return path, range_problem(error.instance, **{bound: error.validator_value}) or error.message
    if v == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        where = f"{path}." if path else ""
        return f"{where}{extra[0]}" if extra else path, "unknown key (not in the config schema)"
    if v == "required":
        missing = [k for k in error.validator_value if k not in error.instance]
        where = f"{path}." if path else ""
        return f"{where}{missing[0]}" if missing else path, "required"
    if v in ("oneOf", "anyOf"):
        return (
            path,
            f"invalid value {_describe(error.instance)} ({error.schema.get('description', 'see schema')})",
        )
    return path, error.message


def _merge(instance: Any, doc: dict) -> Any:
    for f in dataclasses.fields(instance):
        if f.name not in doc:
            continue
        value = doc[f.name]
        current = getattr(instance, f.name)
        if dataclasses.is_dataclass(current) and isinstance(value, dict):
            _merge(current, value)
        else:
            if isinstance(current, int) and not isinstance(current, bool) and isinstance(value, float):
                value = int(value)  # 2e3 particles (YAML 1.2 numbers); the schema checked it is whole
            setattr(instance, f.name, value)
    return instance


def validate_document(doc: Any, schema_path: Path, where: str) -> None:
    """Raise :class:`InputError` naming the YAML path of the deepest schema violation (NaN and
    infinity first: JSON Schema's ``number`` accepts them)."""
    check_finite_tree(doc, where)
    schema = json.loads(schema_path.read_text(encoding="utf-8"))
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(
        validator.iter_errors(doc), key=lambda e: (len(list(e.absolute_path)), str(e.absolute_path))
    )
    if errors:
        error = max(errors, key=lambda e: len(list(e.absolute_path)))
        path, message = _message(error)
        raise InputError(f"{where}: {path or '(top level)'}: {message}")


def read_yaml(path: Path, what: str) -> Any:
    """The YAML document at ``path``; unreadable or binary files, syntax errors and numbers that are
    not finite raise :class:`InputError` (:func:`bimkit.checks.read_yaml`)."""
    return checks.read_yaml(path, what)


def parse_config(doc: Any, source: Path | None = None) -> SessionConfig:
    where = str(source) if source else "config"
    if doc is None:
        doc = {}
    validate_document(doc, SCHEMA_PATH, where)
    given = given_paths(doc)
    doc = with_reality(doc, (doc.get("sim") or {}).get("reality", "ideal"))
    config = _merge(SessionConfig(), doc)
    config.source = source
    start = config.sim.start
    if start != "random" and not (isinstance(start, list) and len(start) == 3):
        raise InputError(
            f'{where}: sim.start: expected "random" or [x, y, yaw_degrees], got {_describe(start)}'
        )
    if not config.site.path:
        raise InputError(f"{where}: site.path: required (an IFC file or a bim-extract output folder)")
    check_resources(config, where)
    check_config(config, given, where)
    return config


MAX_FILTER_BYTES = 2**30  # the fine-tuning filter's working arrays: particles x beams
MAX_IMAGE_PIXELS = 4096 * 4096  # the camera image the detector renders


def check_resources(config: SessionConfig, where: str) -> None:
    """Memory the session will need, checked before it starts (not met as a MemoryError later)."""
    beams = min(config.lidar.beams, LaserModel().beams)  # the likelihood field uses at most these
    need = config.fine_tuning.particles * beams * 8 * 8  # ~8 float64 arrays of particles x beams
    if config.fine_tuning.enabled and need > MAX_FILTER_BYTES:
        raise InputError(
            f"{where}: fine_tuning.particles: {config.fine_tuning.particles} particles x {beams} beams need "
            f"~{need / 2**30:.1f} GiB (at most {MAX_FILTER_BYTES / 2**30:.0f} GiB); use fewer particles"
        )
    pixels = config.camera.width * config.camera.height
    if pixels > MAX_IMAGE_PIXELS:
        raise InputError(
            f"{where}: camera.width x camera.height: {config.camera.width} x {config.camera.height} = "
            f"{pixels} pixels is above the maximum {MAX_IMAGE_PIXELS} (4096 x 4096)"
        )


def with_reality(doc: dict, reality: str) -> dict:
    """``doc`` with ``sim.reality`` set and the profile's values under the keys ``doc`` leaves unset."""
    doc = copy.deepcopy(doc)
    sim = doc.setdefault("sim", {})
    sim["reality"] = reality
    for section, values in REALITY_PROFILES[reality].items():
        given = sim.setdefault(section, {})
        for key, value in values.items():
            given.setdefault(key, value)
    return doc


def load_config(path: Path, reality: str | None = None) -> SessionConfig:
    """The session config at ``path``; ``reality``: a named profile that replaces ``sim.reality``."""
    path = Path(path)
    doc = read_yaml(path, "config")
    if doc is not None and not isinstance(doc, dict):
        raise InputError(f"{path}: expected a mapping of sections (site, robot, camera, ...)")
    if reality is not None:
        doc = with_reality(doc or {}, reality)
    return parse_config(doc, path)


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


def config_to_dict(config: SessionConfig) -> dict:
    doc = dataclasses.asdict(config)
    doc.pop("source", None)
    return doc


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
    return 1 if config.exploration.wall_side == "left" else -1


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


def main(argv: list[str] | None = None) -> int:
    """``python -m initcli.config``: print the site config's JSON Schema, generated from its
    records; ``--write``: write it to ``bimkit/schemas/site_config.schema.json`` (atomically)."""
    from bimkit.atomic import write_text_atomic

    args = sys.argv[1:] if argv is None else argv
    text = json.dumps(site_config_schema(), indent=2) + "\n"
    if args == ["--write"]:
        write_text_atomic(SCHEMA_PATH, text)
        print(f"wrote {SCHEMA_PATH}")
    elif not args:
        sys.stdout.write(text)
    else:
        print("usage: python -m initcli.config [--write]", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
