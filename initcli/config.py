"""The session config (``site.yaml``): sections, documented defaults, validation.

Validated against ``schemas/site_config.schema.json`` before anything runs; an error names the
YAML path and the problem (``camera.fx: expected a number, got "abc"``).
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jsonschema

from bimkit import checks
from bimkit.checks import check_finite_tree, range_problem
from bimkit.errors import InputError
from bimkit.schemas import schema_path
from initcli.core.particle_filter import LaserModel
from initcli.core.projection import CameraIntrinsics, CameraMount
from initcli.core.verification import VerificationParams
from initcli.core.wall_following import WallFollowParams
from initcli.match.pipeline import MatchOptions
from initcli.sim.as_built import AsBuiltParams

SCHEMA_PATH = schema_path("site_config.schema.json")
_MATCH = MatchOptions()  # the one default of every matching setting


@dataclass
class SiteSection:
    path: str = ""  # an IFC file or a bim-extract OUTDIR, relative to the config file
    storey: str = "auto"


@dataclass
class RosbridgeSection:  # robot.driver: rosbridge (initcli/ros/rosbridge_driver.py)
    host: str = "localhost"
    port: int = 9090
    odom_topic: str = "/odom"  # nav_msgs/Odometry
    scan_topic: str = "/scan"  # sensor_msgs/LaserScan
    detections_topic: str = "/detections"  # vision_msgs/Detection2DArray
    depth_topic: str = "/camera/aligned_depth_to_color/image_raw"  # 16UC1 mm or 32FC1 m
    cmd_vel_topic: str = "/cmd_vel"  # geometry_msgs/Twist


@dataclass
class RobotSection:
    driver: str = "sim"  # sim | rosbridge
    radius: float = 0.3  # m
    max_linear: float = 0.5  # m/s
    max_angular: float = 1.0  # rad/s
    drive: bool = True  # rosbridge: false listens only while a person drives
    rosbridge: RosbridgeSection = field(default_factory=RosbridgeSection)


@dataclass
class CameraPose:
    x: float = 0.2
    y: float = 0.0
    z: float = 1.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0


@dataclass
class CameraSection:
    fx: float = 320.0  # 640x480 at ~90 degrees horizontal field of view (Intel D455 colour)
    fy: float = 320.0
    cx: float = 320.0
    cy: float = 240.0
    width: int = 640
    height: int = 480
    pose: CameraPose = field(default_factory=CameraPose)
    depth_noise: float = 0.005  # sigma = depth_noise * d^2: 2 % at 4 m (D455)
    range: float = 6.0  # m: objects are detected up to this distance
    max_view_angle: float = 75.0  # degrees from an element's normal
    depth_window: int = 2  # n of the (2n+1)x(2n+1) depth window


@dataclass
class LidarSection:
    beams: int = 360
    fov: float = 360.0  # degrees
    max_range: float = 20.0  # m
    noise: float = 0.02  # m standard deviation
    dropout: float = 0.01  # fraction of beams returning nothing


@dataclass
class DetectorSection:
    kind: str = "simulated"  # simulated | onnx
    model: str = "default"
    score_threshold: float = _MATCH.score_threshold
    rate: float = 5.0  # Hz
    classes: dict[str, str] = field(default_factory=dict)  # detector class -> feature category


@dataclass
class MatchingSection:
    """Every matching tunable of ``bim-init match`` (same names, units and defaults: the defaults are
    :class:`initcli.match.pipeline.MatchOptions`'s), and the session's own ``m_thre`` and
    ``drift_window``. The detection filter's score threshold is ``detector.score_threshold`` and the
    wall clearance of Eq. 17 ``exploration.d_thre``."""

    alpha: float = _MATCH.alpha  # m, Eq. 7
    beta: float = _MATCH.beta  # degrees, Eq. 9
    max_outliers: int = _MATCH.max_outliers
    outlier_share: float = _MATCH.outlier_share  # share of the features the budget grows to
    revisits: bool = _MATCH.revisits
    pose_method: str = _MATCH.pose_method
    pose_window: int = _MATCH.pose_window  # rigid: the last N matched features; 0: all
    min_sightings: int = _MATCH.min_sightings
    merge_radius: float = _MATCH.merge_radius  # m
    min_depth: float = _MATCH.min_depth  # m
    max_depth: float = _MATCH.max_depth  # m
    edge_margin: float = _MATCH.edge_margin  # px
    m_thre: int = 40  # active exploration only with fewer hypotheses than this
    drift_window: float = 50.0  # m: with no consistent match, retry with the features of the last M m


@dataclass
class ExplorationSection:
    wall_side: str = "left"
    wall_distance: float = 0.7  # m kept to the followed wall
    d_thre: float = _MATCH.d_thre  # m, Eq. 17
    t_thre: float = 25.0  # s without a new feature during active exploration -> recovery
    # §3.3.4's BIM-based active exploration (several but fewer than matching.m_thre hypotheses, or
    # a claim's credible rivals); off: wall following until one hypothesis is left
    active: bool = False
    max_route: float = 0.0  # m: active exploration takes no target farther along the corridors; 0: any
    recovery: bool = True
    initial_look: bool = True  # turn once on the spot before exploring
    # m of travel without a new feature while following a wall with open space on the other side
    # (a hall, a car park, an open-plan office) -> turn once on the spot again; 0: never
    look_every: float = 10.0
    # after this many such looks since the last new feature (60 m of open floor with the
    # defaults), drive across the open floor to a wall the lidar sees and follow it; 0: never
    cross_after: int = 6


@dataclass
class FineTuningSection:
    enabled: bool = True
    particles: int = 2000
    covariance: float = 0.01  # m^2: x and y variance must fall below this
    yaw_covariance: float = 0.0012  # rad^2 (2 degrees)
    distance: float = 6.0  # m followed along the wall at most
    seed_sigma_xy: float = 0.5  # m
    seed_sigma_yaw: float = 10.0  # degrees


@dataclass
class LimitsSection:
    max_distance: float = 150.0  # m driven without a unique match -> failure (paper §4.3)
    max_time: float = 1200.0  # s of session time


@dataclass
class OdometryNoiseSection:
    """Drift of the robot's odometry (wheels fused with the IMU, as on the paper's robot); variances
    grow with each step's motion: rotation alpha1 rad^2/rad + alpha2 rad^2/m, translation
    alpha3 m^2/m + alpha4 m^2/rad (see initcli.sim.robot)."""

    alpha1: float = 0.0001
    alpha2: float = 0.00001
    alpha3: float = 0.0004
    alpha4: float = 0.0001


_AS_BUILT = AsBuiltParams()  # the one default of every as-built deviation (all 0: the design)
_CHECKS = VerificationParams()  # the one default of every verification threshold


@dataclass
class AsBuiltSection:
    """How the simulated site deviates from its design model (initcli.sim.as_built)."""

    missing_doors: float = _AS_BUILT.missing_doors  # share of doors not installed
    door_shift: float = _AS_BUILT.door_shift  # m, sigma along the host wall
    wall_offset: float = _AS_BUILT.wall_offset  # m, sigma per element
    open_doors: float = _AS_BUILT.open_doors  # share of installed doors standing open
    hoarding: float = _AS_BUILT.hoarding  # temporary walls per 100 m of corridor
    extra_doors: float = _AS_BUILT.extra_doors  # doors the model lacks, per 100 m of corridor
    clutter_in_corridor: float = _AS_BUILT.clutter_in_corridor  # share of stacks out in the corridor


@dataclass
class SimDetectorSection:
    """What the simulated detector gets wrong persistently (beyond sim.miss_rate per image)."""

    persistent_phantoms: float = _AS_BUILT.persistent_phantoms  # per 100 m: posters detected as doors
    never_seen: float = _AS_BUILT.never_seen  # share of real features never detected


@dataclass
class SimOdometrySection:
    """Systematic odometry errors (on top of sim.odometry_noise's random walk)."""

    scale_error: float = 0.0  # share of distance counted too far (0.02: 2 % wheel-radius error)
    slip: float = 0.0  # wheel-slip events per 100 m


# Named realities (sim.reality): values for the keys above that the config does not set itself.
REALITY_PROFILES: dict[str, dict[str, dict[str, float]]] = {
    "ideal": {},
    "construction": {
        "as_built": {
            "missing_doors": 0.2,
            "door_shift": 0.3,
            "wall_offset": 0.05,
            "open_doors": 0.3,
            "hoarding": 1.0,
            "extra_doors": 0.5,
            "clutter_in_corridor": 0.5,
        },
        "detector": {"persistent_phantoms": 1.0, "never_seen": 0.1},
        "odometry": {"scale_error": 0.02, "slip": 1.0},
    },
}


@dataclass
class SimSection:
    start: Any = "random"  # "random" or [x, y, yaw_degrees] in the BIM frame
    world: str = ""  # the building the robot drives in (IFC or bim-extract OUTDIR); "": site.path
    reality: str = "ideal"  # a named profile of the keys below (REALITY_PROFILES)
    as_built: AsBuiltSection = field(default_factory=AsBuiltSection)
    detector: SimDetectorSection = field(default_factory=SimDetectorSection)
    odometry: SimOdometrySection = field(default_factory=SimOdometrySection)
    odometry_noise: OdometryNoiseSection = field(default_factory=OdometryNoiseSection)
    clutter: float = 0.05  # material stacks per metre of corridor wall
    workers: int = 2
    miss_rate: float = 0.1  # chance a visible feature is not detected in an image
    false_positives_per_minute: float = 1.0
    confusion_rate: float = 0.02  # chance a detection gets another class
    phantoms: int = 0  # persistent door-like things that are not in the BIM (posters, openings)
    seed: int = 1


@dataclass
class VerificationSection:
    """Checks of a unique match before it is claimed (initcli.core.verification)."""

    enabled: bool = _CHECKS.enabled
    predict_range: float = _CHECKS.predict_range  # m
    min_frames: int = _CHECKS.min_frames  # images in view before a miss counts
    match_radius: float = _CHECKS.match_radius  # m
    p_right: float = _CHECKS.p_right  # miss chance of a predicted feature at the right place
    p_wrong: float = _CHECKS.p_wrong  # ... and at a wrong place
    log_odds: float = _CHECKS.log_odds  # likelihood ratio (natural log) that rejects
    min_scan_fit: float = _CHECKS.min_scan_fit  # share of beams on mapped walls
    min_fine_scan_fit: float = _CHECKS.min_fine_scan_fit  # ... at the fine pose
    min_path_free: float = _CHECKS.min_path_free  # share of the recent path on free BIM cells
    scan_tolerance: float = _CHECKS.scan_tolerance  # m
    min_claim_inliers: int = _CHECKS.min_claim_inliers  # matched features before a claim
    rival_outliers: int = _CHECKS.rival_outliers  # extra outliers the claim must stay unique under
    outrank_outliers: int = _CHECKS.outrank_outliers  # a credible rival this many outliers worse ...
    outrank_scan_fit: float = _CHECKS.outrank_scan_fit  # ... and this much worse a scan fit: no doubt
    track_m: float = _CHECKS.track_m  # m of the path whose scans are fitted window by window ...
    track_lead: float = _CHECKS.track_lead  # ... a place fitting some window this much better ...
    track_slack: float = _CHECKS.track_slack  # ... and none this much worse outranks another ...
    min_track_fit: float = _CHECKS.min_track_fit  # ... when it fits every window at least this well
    track_lead_trailing: float = _CHECKS.track_lead_trailing  # the lead over one outrank_outliers worse
    min_track_windows: int = _CHECKS.min_track_windows  # windows two places are compared on, at least


@dataclass
class SessionConfig:
    site: SiteSection = field(default_factory=SiteSection)
    robot: RobotSection = field(default_factory=RobotSection)
    camera: CameraSection = field(default_factory=CameraSection)
    lidar: LidarSection = field(default_factory=LidarSection)
    detector: DetectorSection = field(default_factory=DetectorSection)
    matching: MatchingSection = field(default_factory=MatchingSection)
    exploration: ExplorationSection = field(default_factory=ExplorationSection)
    fine_tuning: FineTuningSection = field(default_factory=FineTuningSection)
    limits: LimitsSection = field(default_factory=LimitsSection)
    sim: SimSection = field(default_factory=SimSection)
    verification: VerificationSection = field(default_factory=VerificationSection)
    source: Path | None = None  # the YAML file

    def site_path(self) -> Path:
        base = self.source.parent if self.source else Path.cwd()
        return (base / self.site.path).resolve()


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
    a, d = config.sim.as_built, config.sim.detector
    return AsBuiltParams(
        **dataclasses.asdict(a), persistent_phantoms=d.persistent_phantoms, never_seen=d.never_seen
    )


def verification_params(config: SessionConfig) -> VerificationParams:
    return dataclasses.replace(_CHECKS, **dataclasses.asdict(config.verification))


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
    """The session's matching options: the ``matching:`` section, ``detector.score_threshold`` and
    ``exploration.d_thre``; enough hypotheses are kept to decide on active exploration (``m_thre``)."""
    m = config.matching
    return MatchOptions(
        storey=storey,
        alpha=m.alpha,
        beta=m.beta,
        top=max(m.m_thre, _MATCH.top),
        max_outliers=m.max_outliers,
        outlier_share=m.outlier_share,
        revisits=m.revisits,
        pose_method=m.pose_method,
        pose_window=m.pose_window,
        d_thre=config.exploration.d_thre,
        merge_radius=m.merge_radius,
        min_sightings=m.min_sightings,
        score_threshold=config.detector.score_threshold,
        min_depth=m.min_depth,
        max_depth=m.max_depth,
        edge_margin=m.edge_margin,
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
        front_stop=config.robot.radius + 0.2,
    )


def turn_in_place_speed(config: SessionConfig) -> float:
    """rad/s of the look round at the start and of the recovery rotation (§3.3.4)."""
    return 0.6 * config.robot.max_angular


def camera_of(config: SessionConfig) -> tuple[CameraIntrinsics, CameraMount]:
    """The camera's intrinsics and its mount on the robot (``camera:``)."""
    c = config.camera
    intrinsics = CameraIntrinsics(c.fx, c.fy, c.cx, c.cy, int(c.width), int(c.height))
    p = c.pose
    return intrinsics, CameraMount(p.x, p.y, p.z, p.roll, p.pitch, p.yaw)
