"""The simulated robot in its world, built from a session config: the storey as built (doors missing,
shifted or open, hoardings, extra doors), material stacks and walking workers, a start a robot can
stand on, the odometry noise, the camera (simulated detector or a rendered view and a network) and
the lidar; shared by ``bim-init run``, the evaluation's trials and the baselines."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import Site, StoreyModel
from bimtools.site.records import FREE, OCCUPIED
from initcli.config import SessionConfig, as_built_params, camera_of, start_pose_degrees
from initcli.config.building import world_storey
from initcli.config.checks import detector_profile, lidar_profile
from initcli.core.features.classes import ClassMap
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import DetectedObject
from initcli.io.lidar_profile import LidarProfile
from initcli.sim.as_built import HOARDING_CLASS, AsBuiltWorld, derive_as_built, stand_out
from initcli.sim.camera import CameraNoise, SimulatedDetector
from initcli.sim.driver import LidarSpec, SimDriver
from initcli.sim.fence import site_fence
from initcli.sim.robot import DiffDriveRobot, OdometryNoise
from initcli.sim.scenario import place_clutter, place_workers, random_start
from initcli.sim.synthetic_log import sim_features_from_bim
from initcli.sim.world import SimWorld, world_edges
from initcli.storey.circulation import Circulation
from initcli.storey.doors import LEAF_CLASS, door_ids

__all__ = ["SimSetup", "build_sim", "check_clearance", "check_start"]


START_MARGIN = 0.15  # m beyond the robot's radius: gaps narrower than 2 (radius + this) do not connect


AS_BUILT_SEED = 104729  # the as-built world draws from its own generator: the same starts at every value


@dataclass
class SimSetup:
    driver: SimDriver
    start: Pose2D
    world: SimWorld
    storey: str
    as_built: AsBuiltWorld | None = None  # what differs from the design (None: the ideal world)
    enclosed: bool = False  # the start lies in a space closed off (doors, hoardings, narrow gaps)


def build_sim(
    config: SessionConfig,
    site: Site,
    storey: str,
    seed: int,
    start: Pose2D | None = None,
    detect_features: bool = True,
    world_site: Site | None = None,
) -> SimSetup:
    """The simulated robot in the storey's world. ``detect_features=False`` leaves the feature
    detector out (methods that do not use it: the world, start and noise are the same)."""
    check_start(config, site.storeys[storey], start)
    rng = np.random.default_rng(seed)
    model = world_storey(site, world_site, storey)
    circulation = Circulation.of(model)
    measured = lidar_profile(config)  # lidar.profile: noise, dropout and clutter measured on real logs
    built, clutter = _as_built(config, model, circulation, seed, rng, measured)
    # Where the free space reaches the outside (an open gate, a façade not built), the world ends
    # at the building's footprint (initcli.sim.fence).
    built.obstacles.extend(site_fence(model.grid))
    static = SimWorld.from_obstacles(built.obstacles, clutter)
    workers = place_workers(model, circulation, static.static, int(config.sim.people), rng)
    world = SimWorld.from_obstacles(built.obstacles, clutter, workers)
    # Starts lie where a robot can be: the free space connected to the corridors with the doors as
    # the simulated world has them (closed leaves, hoardings), material stacks, and the robot's size.
    closed = [o for o in built.obstacles if o.ifc_class in (LEAF_CLASS, HOARDING_CLASS)]
    reachable = Circulation.of(
        model, closed=closed, boxes=clutter, footprint=config.robot.radius + START_MARGIN
    )
    start, enclosed = _start(config, start, reachable, world, rng)
    n = config.sim.odometry_noise
    o = config.sim.odometry
    noise_model = OdometryNoise(n.alpha1, n.alpha2, n.alpha3, n.alpha4, o.scale_error, o.slip)
    robot = DiffDriveRobot(start, config.robot.radius, noise_model, rng)
    camera, mount = camera_of(config)
    phantoms = _phantoms(model, circulation, int(config.sim.phantoms), rng)
    detector: Callable[[Pose2D, float], list[DetectedObject]]
    if not detect_features:
        detector = _no_detections
    elif config.detector.kind == "onnx":
        from initcli.sim.onnx_camera import OnnxCamera, OnnxCameraSpec

        onnx = OnnxCameraSpec(
            config.detector.model,
            config.detector.score_threshold,
            config.camera.depth_window,
            config.camera.depth_noise,
            config.camera.min_range,
            config.camera.range,
            config.detector.classes,
        )
        detector = OnnxCamera(onnx, model, world, camera, mount, rng).detect
    else:
        detector = SimulatedDetector(
            built.features + phantoms,
            camera,
            mount,
            _camera_noise(config),
            config.detector.rate,
            world,
            rng,
            detector_profile(config),
        ).detect
    spec = config.lidar
    noise, dropout = (measured.noise, measured.dropout) if measured else (spec.noise, spec.dropout)
    lidar = LidarSpec(int(spec.beams), math.radians(spec.fov), spec.max_range, noise, dropout)
    driver = SimDriver(
        world,
        robot,
        lidar,
        camera,
        mount,
        detector,
        config.detector.rate,
        config.robot.max_linear,
        config.robot.max_angular,
        rng,
        depth_window=int(config.camera.depth_window),
    )
    ideal = built.changes == {}
    return SimSetup(driver, start, world, storey, None if ideal else built, enclosed)


def _as_built(
    config: SessionConfig,
    model: StoreyModel,
    circulation: Circulation,
    seed: int,
    rng: np.random.Generator,
    measured: LidarProfile | None = None,
) -> tuple[AsBuiltWorld, list[np.ndarray]]:
    """The storey as built (from its own generator, so that the starts are the same at every
    as-built setting) and the material stacks placed in it (from ``rng``; ``sim.clutter`` of them
    per metre of corridor wall, or the lidar profile's)."""
    cmap = ClassMap(config.detector.classes)
    design = sim_features_from_bim(model.camera_features, cmap)  # the camera's; the lidar sees walls
    doors = door_ids(model.features)
    built = derive_as_built(
        model.obstacles,
        model.walls,
        design,
        circulation,
        as_built_params(config),
        np.random.default_rng([seed, AS_BUILT_SEED]),
        doors,
    )
    density = measured.clutter if measured else config.sim.clutter
    clutter = place_clutter(model, circulation, density, rng)
    clutter = stand_out(
        clutter,
        config.sim.as_built.clutter_in_corridor,
        np.random.default_rng([seed, AS_BUILT_SEED, 1]),
        world_edges(built.obstacles, clutter)[0],
    )
    return built, clutter


def _start(
    config: SessionConfig,
    start: Pose2D | None,
    reachable: Circulation,
    world: SimWorld,
    rng: np.random.Generator,
) -> tuple[Pose2D, bool]:
    """The start pose (given, the config's ``sim.start``, or drawn from the reachable free space
    clear of obstacles) and whether a given one lies in a space closed off from the corridors."""
    if start is None:
        explicit = start_pose_degrees(config)
        start = Pose2D(*explicit) if explicit is not None else None
    enclosed = False
    if start is None:
        for _ in range(200):
            start = random_start(reachable, rng, clearance=config.robot.radius + 0.3)
            if world.clearance(start.x, start.y, 0.0, 1.0) > config.robot.radius + 0.2:
                break
    else:
        check_clearance(start, world, config.robot.radius)
        enclosed = not reachable.reaches(start.x, start.y, within=config.robot.radius + START_MARGIN)
    assert start is not None
    return start, enclosed


def _camera_noise(config: SessionConfig) -> CameraNoise:
    """The simulated detector's noise: misses, false positives, confusions, depth noise, range."""
    return CameraNoise(
        miss_rate=config.sim.miss_rate,
        false_positives_per_minute=config.sim.false_positives_per_minute,
        confusion_rate=config.sim.confusion_rate,
        depth_noise_quad=config.camera.depth_noise,
        range=config.camera.range,
        max_view_angle_deg=config.camera.max_view_angle,
    )


def check_clearance(start: Pose2D, world: SimWorld, radius: float) -> None:
    """A start against an obstacle of the simulated world (clutter, a hoarding) is bad input."""
    if world.clearance(start.x, start.y, 0.0, 1.0) < radius:
        raise InputError(f"sim.start ({start.x:.2f}, {start.y:.2f}): inside or against an obstacle")


def check_start(
    config: SessionConfig, model: StoreyModel, start: Pose2D | None = None, where: str | None = None
) -> None:
    """An explicit start (``--start`` or ``sim.start``) must lie on a free cell of the storey's map:
    outside the building or inside a wall is one :class:`InputError`, before anything runs.
    ``where`` names it in the message (default: ``--start`` for ``start``, else ``sim.start``)."""
    if start is None:
        explicit = start_pose_degrees(config)
        if explicit is None:
            return
        start = Pose2D(*explicit)
        where = where or (f"{config.source}: sim.start" if config.source else "sim.start")
    where = where or "--start"
    at = f"({start.x:g}, {start.y:g})"
    if not all(math.isfinite(v) for v in (start.x, start.y, start.yaw)):
        raise InputError(f"{where}: {at}, {math.degrees(start.yaw):g} degrees is not a finite pose")
    grid = model.grid
    if grid is None:
        return
    from shapely.geometry import Point, Polygon

    point = Point(start.x, start.y)
    for obstacle in model.obstacles:
        if len(obstacle.exterior) >= 3 and Polygon(obstacle.exterior, obstacle.holes).covers(point):
            raise InputError(
                f"{where}: {at} is inside {obstacle.ifc_class} {obstacle.element} on storey {model.name!r}"
            )
    value = grid.value_at(start.x, start.y)
    if value == OCCUPIED:
        raise InputError(f"{where}: {at} is on a wall of storey {model.name!r} (an occupied map cell)")
    if value != FREE:
        x0, y0 = grid.origin[0], grid.origin[1]
        x1 = x0 + grid.shape[1] * grid.resolution
        y1 = y0 + grid.shape[0] * grid.resolution
        raise InputError(
            f"{where}: {at} is outside the building on storey {model.name!r} (its map spans "
            f"x {x0:.1f}..{x1:.1f}, y {y0:.1f}..{y1:.1f} m; a start must be on a free cell)"
        )


def _no_detections(pose: Pose2D, t: float) -> list[DetectedObject]:
    return []


def _phantoms(model, circulation: Circulation, count: int, rng: np.random.Generator):
    """Door-like things on corridor walls that are not in the BIM (posters, temporary openings)."""
    from initcli.sim.synthetic_log import SimFeature

    walls = [
        w
        for w in model.walls
        if w.length > 2.0
        and circulation.contains((w.x1 + w.x2) / 2 + 0.4 * w.normal[0], (w.y1 + w.y2) / 2 + 0.4 * w.normal[1])
    ]
    out = []
    for i in range(min(count, len(walls))):
        w = walls[int(rng.integers(len(walls)))]
        s = rng.uniform(0.2, 0.8)
        out.append(
            SimFeature(
                f"phantom-{i}",
                "door",
                w.x1 + s * (w.x2 - w.x1),
                w.y1 + s * (w.y2 - w.y1),
                w.normal[0],
                w.normal[1],
                1.0,
                2.1,
            )
        )
    return out
