"""Synthetic detection logs: BIM features + a true robot path -> a version-1 detection log.

Each camera image renders the BIM features in view with the inverse of Eq. 1-2
(:mod:`initcli.core.geometry.projection`): the element's centre at ``centre_height`` of its height is
projected to a pixel, the box is sized from the element's width and height, and ``depth`` is the
optical depth z_c (plus optional noise). Applying Eq. 1-2 to such a box returns the feature's
position exactly, so a noise-free log reproduces the BIM layout in the odom frame.

A feature is visible when it is in the image, within ``[min_range, max_range]``, seen from the
front (its normal within ``max_view_angle`` of the line of sight) and, when walls are given, not
hidden behind a wall surface. The odom frame is the start pose (§3.3.1); ``truth`` records carry
the true BIM pose. Used by the tests and the benchmark, and meant for the simulator.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from initcli.core.features.classes import ClassMap
from initcli.core.geometry.projection import (
    DEFAULT_CAMERA,
    DEFAULT_MOUNT,
    CameraIntrinsics,
    CameraMount,
    box_for_point,
    odom_to_pixel,
)
from initcli.core.geometry.raycast import sight_blocked
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.io.detection_log import DetectedObject, Detections, Meta, Odom, Record, Truth

__all__ = [
    "SimFeature",
    "SyntheticLog",
    "SyntheticParams",
    "false_box",
    "make_log",
    "path_from_waypoints",
    "render_image",
    "sim_features_from_bim",
]


@dataclass(frozen=True)
class SimFeature:
    """Anything the detector may report: a BIM feature, or a *phantom* (a poster that looks like a door)."""

    id: str
    cls: str
    x: float
    y: float
    norm_x: float = 1.0
    norm_y: float = 0.0
    width: float = 1.0
    height: float = 2.1


@dataclass(frozen=True)
class SyntheticParams:
    rate_hz: float = 5.0  # images (and odom records) per second
    min_range: float = 0.5  # m
    max_range: float = 6.0  # m
    max_view_angle: float = math.radians(80.0)  # rad from the feature's normal
    centre_height: float = 0.5  # box centre at this fraction of the element's height
    depth_noise: float = 0.0  # m, standard deviation added to the depth
    depth_noise_quad: float = 0.0  # 1/m: further std of depth_noise_quad * D^2 (stereo depth error)
    pixel_noise: float = 0.0  # px, standard deviation added to the box corners
    clip_boxes: bool = False  # clip boxes to the image as a real detector does (biases the centre)
    score: float = 0.9
    false_positive_rate: float = 0.0  # per image: chance of one random, non-persistent false box
    odom_noise: tuple[float, float] = (0.0, 0.0)  # std per metre travelled, per radian turned
    detect_probability: float = 1.0  # chance that a visible feature is detected in an image
    empty_detections: bool = False  # also write detections records with no objects


@dataclass
class SyntheticLog:
    records: list[Record]
    final_pose: Pose2D  # true BIM pose at the last odom record
    start_pose: Pose2D  # the BIM pose of the odom origin
    seen: list[str] = field(default_factory=list)  # ids of features detected at least once, first-seen order


def sim_features_from_bim(features: Sequence, class_map: ClassMap | None = None) -> list[SimFeature]:
    """``bimtools.site.records.Feature`` objects -> :class:`SimFeature` with canonical class names."""
    cmap = class_map or ClassMap()
    return [
        SimFeature(str(f.id), cmap.canonical(f.category), f.x, f.y, f.norm_x, f.norm_y, f.width, f.height)
        for f in features
    ]


def path_from_waypoints(
    waypoints: Sequence[tuple[float, float]],
    speed: float = 0.5,
    turn_rate: float = 0.8,
    rate_hz: float = 5.0,
    start_yaw: float | None = None,
    end_yaw: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A true path through the waypoints: turn in place toward the next one, then drive straight.

    Returns times (T,) and BIM poses (T, 3) sampled at ``rate_hz``.
    """
    pts = np.asarray(waypoints, dtype=float).reshape(-1, 2)
    dt = 1.0 / rate_hz
    poses: list[tuple[float, float, float]] = []
    yaw = (
        start_yaw
        if start_yaw is not None
        else (math.atan2(pts[1, 1] - pts[0, 1], pts[1, 0] - pts[0, 0]) if len(pts) > 1 else 0.0)
    )
    x, y = pts[0]
    poses.append((x, y, yaw))

    def turn_to(target: float) -> None:
        nonlocal yaw
        while True:
            err = float(wrap_angle(target - yaw))
            step = turn_rate * dt
            if abs(err) <= step:
                yaw = target
                poses.append((x, y, yaw))
                return
            yaw = float(wrap_angle(yaw + math.copysign(step, err)))
            poses.append((x, y, yaw))

    for nx, ny in pts[1:]:
        heading = math.atan2(ny - y, nx - x)
        if abs(float(wrap_angle(heading - yaw))) > 1e-12:
            turn_to(heading)
        dist = math.hypot(nx - x, ny - y)
        steps = max(1, math.ceil(dist / (speed * dt)))
        x0, y0 = x, y
        for k in range(1, steps + 1):
            x, y = x0 + (nx - x0) * k / steps, y0 + (ny - y0) * k / steps
            poses.append((x, y, yaw))
    if end_yaw is not None:
        turn_to(end_yaw)
    arr = np.array(poses)
    return np.arange(len(arr)) * dt, arr


def render_image(
    features: Sequence[SimFeature],
    robot_bim: Pose2D,
    camera: CameraIntrinsics = DEFAULT_CAMERA,
    mount: CameraMount = DEFAULT_MOUNT,
    params: SyntheticParams | None = None,
    walls: np.ndarray | None = None,
    rng: np.random.Generator | None = None,
    classes: Sequence[str] = ("door",),
) -> list[tuple[DetectedObject, str | None]]:
    """The detections of one image taken at ``robot_bim`` (inverse Eq. 1-2), with the source feature id."""
    p = params or SyntheticParams()
    rng = rng or np.random.default_rng(0)
    out: list[tuple[DetectedObject, str | None]] = []
    if features:
        xy = np.array([[f.x, f.y] for f in features], dtype=float)
        normals = np.array([[f.norm_x, f.norm_y] for f in features], dtype=float)
        z = np.array([f.height * p.centre_height for f in features], dtype=float)
        u, v, depth = odom_to_pixel(np.column_stack([xy, z]), camera, mount, robot_bim)  # inverse of Eq. 1-2
        eye = robot_bim.apply(np.array([mount.x, mount.y]))
        to_eye = eye - xy
        dist = np.hypot(to_eye[:, 0], to_eye[:, 1])
        cos_view = np.einsum("ij,ij->i", normals, to_eye) / np.maximum(dist, 1e-12)
        visible = (
            (depth >= p.min_range)
            & (depth <= p.max_range)
            & (u >= 0)
            & (u <= camera.width)
            & (v >= 0)
            & (v <= camera.height)
            & (cos_view >= math.cos(p.max_view_angle))
        )
        if walls is not None and visible.any():
            idx = np.flatnonzero(visible)
            targets = xy[idx] + 0.05 * normals[idx]  # just in front of the wall surface
            visible[idx[sight_blocked(eye, targets, np.asarray(walls, dtype=float).reshape(-1, 4))]] = False
        for i in np.flatnonzero(visible):
            if p.detect_probability < 1.0 and rng.random() > p.detect_probability:
                continue
            f = features[int(i)]
            box = np.array(box_for_point(u[i], v[i], depth[i], f.width, f.height, camera))
            if p.pixel_noise > 0:
                box = box + rng.normal(0.0, p.pixel_noise, 4)
            if p.clip_boxes:
                box = np.clip(box, [0, 0, 0, 0], [camera.width, camera.height, camera.width, camera.height])
            sigma = p.depth_noise + p.depth_noise_quad * float(depth[i]) ** 2
            d = float(depth[i] + (rng.normal(0.0, sigma) if sigma > 0 else 0.0))
            out.append((DetectedObject(f.cls, p.score, tuple(float(b) for b in box), d), f.id))  # type: ignore[arg-type]
    if p.false_positive_rate > 0 and rng.random() < p.false_positive_rate:
        false, d = false_box(camera, p, rng)
        fake = DetectedObject(str(rng.choice(list(classes))), p.score, false, d)
        out.append((fake, None))
    return out


def false_box(
    camera: CameraIntrinsics, p: SyntheticParams, rng: np.random.Generator
) -> tuple[tuple[float, float, float, float], float]:
    """A transient false box: a 1 m x 2 m thing centred on a random pixel at a random depth within
    ``[min_range, max_range]`` (the box, clipped as ``p`` says, and the depth)."""
    cu, cv = rng.uniform(0, camera.width), rng.uniform(0, camera.height)
    d = float(rng.uniform(p.min_range, p.max_range))
    box = np.array(box_for_point(cu, cv, d, 1.0, 2.0, camera))
    if p.clip_boxes:
        box = np.clip(box, [0, 0, 0, 0], [camera.width, camera.height, camera.width, camera.height])
    return (float(box[0]), float(box[1]), float(box[2]), float(box[3])), d


def make_log(
    features: Sequence[SimFeature],
    times: np.ndarray,
    path_bim: np.ndarray,
    *,
    camera: CameraIntrinsics = DEFAULT_CAMERA,
    mount: CameraMount = DEFAULT_MOUNT,
    params: SyntheticParams | None = None,
    walls: np.ndarray | None = None,
    phantoms: Sequence[SimFeature] = (),
    seed: int = 0,
    truth: bool = True,
    source: str = "initcli.sim.synthetic_log",
    transform_odom: Callable[[Pose2D], Pose2D] | None = None,
) -> SyntheticLog:
    """Render a whole log along ``path_bim`` (T, 3) at ``times`` (T,).

    ``phantoms`` are rendered like features but are not in the BIM (persistent false positives);
    ``walls`` (W, 4) occlude. Odom poses are the true poses relative to the start pose, with
    optional drift (``params.odom_noise``); ``transform_odom`` maps them further (tests of
    invariance under a rigid change of the odom frame).
    """
    p = params or SyntheticParams()
    rng = np.random.default_rng(seed)
    everything = [*features, *phantoms]
    classes = sorted({f.cls for f in features}) or ["door"]
    path = np.asarray(path_bim, dtype=float).reshape(-1, 3)
    start = Pose2D(*(float(v) for v in path[0]))
    records: list[Record] = [
        Meta(camera=camera, camera_pose=mount, depth_window=2, source=source),
    ]
    seen: list[str] = []
    odom = Pose2D.identity()
    prev_true = start
    for k, (t, row) in enumerate(zip(np.asarray(times, dtype=float), path, strict=True)):
        true = Pose2D(*row)
        if k == 0:
            odom = Pose2D.identity()
        else:
            step = prev_true.inverse() * true  # true motion in the robot frame
            sigma_t, sigma_r = p.odom_noise
            if sigma_t > 0 or sigma_r > 0:
                dist = math.hypot(step.x, step.y)
                step = Pose2D(
                    step.x + rng.normal(0.0, sigma_t * dist) if dist > 0 else step.x,
                    step.y + rng.normal(0.0, sigma_t * dist) if dist > 0 else step.y,
                    step.yaw + (rng.normal(0.0, sigma_r * abs(step.yaw)) if step.yaw else 0.0),
                )
            odom = odom * step
        prev_true = true
        shown = transform_odom(odom) if transform_odom else odom
        t = float(t)
        records.append(Odom(t, shown.x, shown.y, shown.yaw))
        objects = render_image(everything, true, camera, mount, p, walls, rng, classes)
        for _obj, fid in objects:
            if fid is not None and fid not in seen:
                seen.append(fid)
        if objects or p.empty_detections:
            records.append(Detections(t, shown, tuple(o for o, _ in objects)))
        if truth:
            records.append(Truth(t, true.x, true.y, true.yaw))
    final = Pose2D(*(float(v) for v in path[-1]))
    return SyntheticLog(records=records, final_pose=final, start_pose=start, seen=seen)
