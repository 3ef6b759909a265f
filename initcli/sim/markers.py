"""The ArUco marker baseline of §4.3: where the tags go, what the camera sees of them, and the
robot pose one decoded tag gives.

§4.3: "two ArUco tags were deployed for each section and the location was the exact middle of
each corridor segment. Therefore, there were six markers in total, evenly distributed throughout
the entire working environment. The 20 cm x 20 cm markers were printed on paper and pasted on the
walls. The RGBD camera was used to detect the marker using OpenCV library and then estimate the
robot location by decoding the unique marker."

Frames: the BIM frame is the world (x, y on the floor plan, z up); the camera conventions are
those of :mod:`initcli.core.geometry.projection` (optical: x right, y down, z forward). A marker's own
frame is OpenCV's ArUco frame: origin at the tag centre, x to the right and y up as a viewer in
front of the tag sees it, z out of the wall (along the wall normal, into free space).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bimtools.site.load import StoreyModel
from bimtools.site.records import WallSegment
from initcli.core.features.marker_pose import tag_object_points, tag_rotation
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, odom_to_optical
from initcli.core.geometry.raycast import ray_segment_distances, sight_blocked
from initcli.core.geometry.se2 import Pose2D
from initcli.sim.world import SimWorld
from initcli.storey.circulation import Circulation

__all__ = [
    "FEATURE_CLEARANCE",
    "MARKER_HEIGHT",
    "MARKER_SIZE",
    "MAX_CORRIDOR_WIDTH",
    "MAX_SHIFT",
    "MIN_SECTION_LENGTH",
    "Marker",
    "MarkerDetector",
    "MarkerParams",
    "SHIFT_STEP",
    "WALL_CLEARANCE",
    "camera_position",
    "detect_markers",
    "place_markers",
    "project_marker",
]

MARKER_SIZE = 0.2  # m: "20 cm x 20 cm markers" (§4.3)
MARKER_HEIGHT = 1.0  # m: tag centre above the floor (the sample configs' camera height)
MAX_CORRIDOR_WIDTH = 6.0  # m: two facing walls further apart than this do not make one section
MIN_SECTION_LENGTH = 4.0  # m: shorter facing-wall overlaps are not corridor sections
WALL_CLEARANCE = 0.4  # m: a wall faces circulation when this far in front of its midpoint is
FEATURE_CLEARANCE = 0.4  # m: kept between a tag and the edge of a door, lift or staircase
MAX_SHIFT = 3.0  # m: how far a tag may move along its wall off a door opening
SHIFT_STEP = 0.25  # m


@dataclass(frozen=True)
class Marker:
    """One ArUco tag pasted on a wall, in the BIM frame (§4.3).

    ``x, y, z``: the tag centre; ``normal``: the wall normal, pointing into free space (the tag
    faces this way); ``yaw``: the heading of that normal; ``size``: the side of the black square.
    ``section``: the corridor section the tag belongs to.
    """

    id: int
    x: float
    y: float
    z: float
    normal: tuple[float, float]
    yaw: float
    size: float = MARKER_SIZE
    section: int = 0

    @property
    def centre(self) -> np.ndarray:
        return np.array([self.x, self.y, self.z])

    def rotation(self) -> np.ndarray:
        """``R_bim_marker``: columns are the tag's x (right), y (up), z (out of the wall) axes."""
        return tag_rotation(self.normal)

    def object_points(self) -> np.ndarray:
        """The 4 corners in the tag frame in the order ``SOLVEPNP_IPPE_SQUARE`` expects:
        top-left, top-right, bottom-right, bottom-left."""
        return tag_object_points(self.size)

    def corners(self) -> np.ndarray:
        """The 4 corners (same order) in the BIM frame, (4, 3)."""
        return self.object_points() @ self.rotation().T + self.centre


@dataclass(frozen=True)
class MarkerParams:
    """The marker baseline's deployment and simulated detector (§4.3).

    Corner noise: each corner pixel coordinate gets Gaussian noise of
    ``sigma_px = noise_base_px + noise_quad_px * d**2`` (``d``: camera to tag centre, metres):
    0.09 px at 2 m, 0.21 px at 4 m, 1.05 px at 10 m. Real ArUco corners are sub-pixel close up,
    while a tag a few pixels wide far away has badly located corners -- the paper's one marker
    failure ("detected the marker from a far distance of over 10 m. There were large errors in the
    detection of corner locations of the small marker"). With the sample camera (640x480,
    fx = 320) one tag seen 30-50 degrees off its normal gives the robot's position to 1-5 cm at
    2-3 m and ~0.1 m at 4 m; seen head-on the tag's tilt is poorly conditioned (15 cm at 2 m);
    beyond 8-10 m the error is metres, often an IPPE mirror solution (see
    ``tests/initcli/core/features/test_marker_pose.py``). With the defaults a 20 cm tag is too small to
    decode past
    ~6 m (``min_side_px``); the paper's far detection needs ``range`` and ``min_side_px`` relaxed
    (a sharper camera).
    """

    count: int = 6  # two per section, three sections (§4.3)
    size: float = MARKER_SIZE  # m
    height: float | None = None  # m: tag centre height; None puts it at the camera's height
    range: float = 8.0  # m: camera to tag centre
    max_view_angle: float = 60.0  # degrees between the tag normal and the line to the camera
    min_side_px: float = 10.0  # shortest tag side in the image that ArUco still decodes
    noise_base_px: float = 0.05  # px
    noise_quad_px: float = 0.01  # px / m^2


# --- placement ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Section:
    """A corridor section: a wall and (when paired) the facing wall across the corridor, over the
    stretch where both exist (``s0..s1`` along ``wall``)."""

    wall: WallSegment
    facing: WallSegment | None
    s0: float
    s1: float
    centre: np.ndarray

    @property
    def length(self) -> float:
        return self.s1 - self.s0


def _unit(w: WallSegment) -> np.ndarray:
    return np.array([w.x2 - w.x1, w.y2 - w.y1]) / w.length


def _faces_circulation(w: WallSegment, circulation: Circulation) -> bool:
    mx, my = (w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2
    return circulation.contains(mx + WALL_CLEARANCE * w.normal[0], my + WALL_CLEARANCE * w.normal[1])


def _sections(walls: list[WallSegment], circulation: Circulation) -> list[_Section]:
    """Paired sections (two facing walls, a corridor between) then lone walls, longest first."""
    paired: list[_Section] = []
    used: set[int] = set()
    for i, a in enumerate(walls):
        na, ua = np.array(a.normal), _unit(a)
        p1 = np.array([a.x1, a.y1])
        for j, b in enumerate(walls):
            if j <= i or float(np.dot(na, b.normal)) > -0.99:
                continue
            q1, q2 = np.array([b.x1, b.y1]), np.array([b.x2, b.y2])
            gap = float(np.dot(q1 - p1, na))
            if not 0.0 < gap <= MAX_CORRIDOR_WIDTH:
                continue
            t1, t2 = sorted((float(np.dot(q1 - p1, ua)), float(np.dot(q2 - p1, ua))))
            s0, s1 = max(0.0, t1), min(a.length, t2)
            if s1 - s0 < MIN_SECTION_LENGTH:
                continue
            centre = p1 + ua * (s0 + s1) / 2 + na * gap / 2
            if not circulation.contains(*centre):
                continue
            paired.append(_Section(a, b, s0, s1, centre))
            used.update((i, j))
    lone = [
        _Section(w, None, 0.0, w.length, np.array([(w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2]))
        for k, w in enumerate(walls)
        if k not in used and w.length >= MIN_SECTION_LENGTH
    ]

    def key(s: _Section) -> tuple[float, float, float]:
        return (-round(s.length, 6), round(float(s.centre[0]), 6), round(float(s.centre[1]), 6))

    return sorted(paired, key=key) + sorted(lone, key=key)


def _spread(sections: list[_Section], wanted: int) -> list[_Section]:
    """The longest section, then repeatedly the one farthest from those already chosen (paired
    sections before lone walls)."""
    if not sections:
        return []
    chosen = [sections[0]]
    rest = sections[1:]
    n_paired = sum(1 for s in sections if s.facing is not None)
    while len(chosen) < wanted and rest:
        pool = [s for s in rest if s.facing is not None] if len(chosen) < n_paired else rest
        pool = pool or rest
        best = max(
            pool,
            key=lambda s: (min(float(np.hypot(*(s.centre - c.centre))) for c in chosen), s.length),
        )
        chosen.append(best)
        rest = [s for s in rest if s is not best]
    return chosen


def _solid_spot(
    wall: WallSegment,
    s_mid: float,
    s_lo: float,
    s_hi: float,
    static: np.ndarray,
    features: np.ndarray,
) -> float:
    """The spot along ``wall`` nearest ``s_mid`` (within ``s_lo..s_hi``) with wall behind it and
    no door, lift or staircase within ``FEATURE_CLEARANCE`` of the tag's edge."""
    u, n = _unit(wall), np.array(wall.normal)
    p1 = np.array([wall.x1, wall.y1])
    steps = int(MAX_SHIFT / SHIFT_STEP)
    for k in range(2 * steps + 1):
        s = s_mid + SHIFT_STEP * ((k + 1) // 2) * (1 if k % 2 else -1)
        if not s_lo + 0.3 <= s <= s_hi - 0.3:
            continue
        p = p1 + u * s
        behind = float(
            ray_segment_distances(p + 0.3 * n, np.array([math.atan2(-n[1], -n[0])]), static, 1.0)[0]
        )
        if behind > 0.35:
            continue  # an opening (door, passage): nothing to paste the tag on
        if len(features):
            gaps = np.hypot(features[:, 0] - p[0], features[:, 1] - p[1]) - features[:, 2] / 2
            if gaps.min() < FEATURE_CLEARANCE + MARKER_SIZE / 2:
                continue
        return s
    return s_mid


def place_markers(
    storey: StoreyModel,
    circulation: Circulation,
    count: int = 6,
    rng: np.random.Generator | None = None,
    *,
    size: float = MARKER_SIZE,
    height: float = MARKER_HEIGHT,
) -> list[Marker]:
    """Deploy ``count`` ArUco tags as in §4.3: two per corridor section, at the middle of the
    section, evenly spread over the storey.

    The rule, for any building:

    1. Candidate walls are the wall surfaces that face the circulation area (a point
       ``WALL_CLEARANCE`` in front of the midpoint is in it, as for the clutter of
       :func:`initcli.sim.scenario.place_clutter`).
    2. A *section* is a corridor: two candidate walls facing each other (opposite normals) at most
       ``MAX_CORRIDOR_WIDTH`` apart, over the stretch where both exist (at least
       ``MIN_SECTION_LENGTH``), with circulation between them. Walls that pair with no other and are
       at least ``MIN_SECTION_LENGTH`` long are lone sections, used only when there are too few
       corridors.
    3. Sections are picked ``count // 2`` times: first the longest; then each time the one whose
       centre is farthest from the centres already picked (ties: the longer).
    4. A corridor section gets its two tags at the middle of the stretch, one on each wall, facing
       each other (so a robot passing either way has one on its camera side); a lone wall gets
       them at one third and two thirds of its length. A tag that falls on an opening or next to a
       door, lift or staircase moves along the wall to the nearest solid spot (steps of
       ``SHIFT_STEP``, at most ``MAX_SHIFT``).

    An odd ``count`` puts the last tag at the middle of the next section's first wall. Tags sit at
    ``height`` (the camera's height) and face the wall normal. With ``rng`` each tag is first
    shifted along its wall by up to +-0.3 m (pasted by hand); without, the placement is a
    deterministic function of the storey. Tag ids are ``0..count-1`` in section order.
    """
    if count <= 0:
        return []
    walls = [w for w in storey.walls if w.length >= 1.0 and _faces_circulation(w, circulation)]
    walls.sort(key=lambda w: (-round(w.length, 6), round(w.x1, 6), round(w.y1, 6), round(w.x2, 6), w.element))
    sections = _spread(_sections(walls, circulation), (count + 1) // 2)
    static = SimWorld.from_obstacles(storey.obstacles).static
    features = np.array([[f.x, f.y, f.width] for f in storey.camera_features]).reshape(-1, 3)

    def jitter() -> float:
        return float(rng.uniform(-0.3, 0.3)) if rng is not None else 0.0

    def on_wall(wall: WallSegment, s_mid: float, s_lo: float, s_hi: float, section: int) -> Marker:
        s = _solid_spot(wall, s_mid + jitter(), s_lo, s_hi, static, features)
        u = _unit(wall)
        nx, ny = wall.normal
        return Marker(
            id=-1,
            x=float(wall.x1 + u[0] * s),
            y=float(wall.y1 + u[1] * s),
            z=height,
            normal=(float(nx), float(ny)),
            yaw=math.atan2(ny, nx),
            size=size,
            section=section,
        )

    placed: list[Marker] = []
    for k, sec in enumerate(sections):
        if sec.facing is not None:
            a, b = sec.wall, sec.facing
            mid = np.array([a.x1, a.y1]) + _unit(a) * (sec.s0 + sec.s1) / 2
            sb = float(np.dot(mid - np.array([b.x1, b.y1]), _unit(b)))
            lo_b = max(0.0, sb - sec.length / 2)
            hi_b = min(b.length, sb + sec.length / 2)
            placed.append(on_wall(a, (sec.s0 + sec.s1) / 2, sec.s0, sec.s1, k))
            placed.append(on_wall(b, sb, lo_b, hi_b, k))
        else:
            w = sec.wall
            placed.append(on_wall(w, w.length / 3, 0.0, w.length * 0.5, k))
            placed.append(on_wall(w, 2 * w.length / 3, w.length * 0.5, w.length, k))
    placed = placed[:count]
    return [Marker(i, m.x, m.y, m.z, m.normal, m.yaw, m.size, m.section) for i, m in enumerate(placed)]


# --- detection ----------------------------------------------------------------------------------


def camera_position(truth: Pose2D, mount: CameraMount) -> np.ndarray:
    """The camera's optical centre in the BIM frame for a robot at ``truth``."""
    xy = truth.apply(np.array([mount.x, mount.y]))
    return np.array([xy[0], xy[1], mount.z])


def project_marker(
    marker: Marker, truth: Pose2D, intrinsics: CameraIntrinsics, mount: CameraMount
) -> tuple[np.ndarray, np.ndarray]:
    """The tag's 4 corners (IPPE_SQUARE order) as pixels ``(4, 2)`` and their depths ``(4,)``."""
    optical = odom_to_optical(marker.corners(), mount, truth)
    z = optical[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = intrinsics.fx * optical[:, 0] / z + intrinsics.cx
        v = intrinsics.fy * optical[:, 1] / z + intrinsics.cy
    return np.column_stack([u, v]), z


def detect_markers(
    markers: list[Marker],
    truth: Pose2D,
    intrinsics: CameraIntrinsics,
    mount: CameraMount,
    world: SimWorld | None,
    params: MarkerParams,
    rng: np.random.Generator | None = None,
    t: float = 0.0,
    miss_rate: float = 0.0,
) -> dict[int, np.ndarray]:
    """What the RGB-D camera at ``truth`` decodes (§4.3): tag id -> noisy corner pixels ``(4, 2)``.

    A tag is decoded when its 4 corners are in front of the camera and inside the image, its
    centre is within ``params.range`` of the camera and at most ``params.max_view_angle`` off its
    normal, its shortest side spans ``params.min_side_px`` pixels, and nothing in ``world`` (walls,
    clutter, workers at time ``t``) cuts the lines of sight to its centre and side edges; then it is
    still missed with probability ``miss_rate``. Corner noise: see :class:`MarkerParams`. Without
    ``rng`` there are no misses and no noise.
    """
    cam = camera_position(truth, mount)
    out: dict[int, np.ndarray] = {}
    segments = None
    for marker in markers:
        to_cam = cam - marker.centre
        d = float(np.linalg.norm(to_cam))
        if d > params.range or d < 1e-6:
            continue
        cos_view = float(np.dot(to_cam[:2], marker.normal)) / d
        if cos_view < math.cos(math.radians(params.max_view_angle)):
            continue
        px, depth = project_marker(marker, truth, intrinsics, mount)
        if np.any(depth <= 0.05):
            continue
        if np.any(px[:, 0] < 0) or np.any(px[:, 0] > intrinsics.width - 1):
            continue
        if np.any(px[:, 1] < 0) or np.any(px[:, 1] > intrinsics.height - 1):
            continue
        sides = np.linalg.norm(px - np.roll(px, -1, axis=0), axis=1)
        if float(sides.min()) < params.min_side_px:
            continue
        if world is not None:
            if segments is None:
                segments = world.segments_at(float(cam[0]), float(cam[1]), params.range + 1.0, t)
            if _occluded(cam[:2], marker, segments):
                continue
        if rng is not None and miss_rate > 0 and rng.random() < miss_rate:
            continue
        if rng is not None:
            sigma = params.noise_base_px + params.noise_quad_px * d * d
            px = px + rng.normal(0.0, sigma, px.shape)
        out[marker.id] = px
    return out


def _occluded(cam_xy: np.ndarray, marker: Marker, segments: np.ndarray) -> bool:
    """Whether a segment cuts the line of sight to the tag centre or either side edge (the tag is
    tested just in front of its wall so the wall itself does not hide it)."""
    n = np.array(marker.normal)
    side = np.array([-n[1], n[0]]) * marker.size / 2
    centre = np.array([marker.x, marker.y]) + 0.02 * n
    targets = np.array([centre, centre + side, centre - side])
    return bool(sight_blocked(cam_xy, targets, segments).any())


class MarkerDetector:
    """The simulated ArUco detector of one run: :func:`detect_markers` with fixed tags, camera,
    world, parameters, miss rate and random stream."""

    def __init__(
        self,
        markers: list[Marker],
        intrinsics: CameraIntrinsics,
        mount: CameraMount,
        world: SimWorld | None,
        params: MarkerParams,
        rng: np.random.Generator | None,
        miss_rate: float = 0.0,
    ):
        self.markers = markers
        self.by_id = {m.id: m for m in markers}
        self.intrinsics = intrinsics
        self.mount = mount
        self.world = world
        self.params = params
        self.rng = rng
        self.miss_rate = miss_rate

    def detect(self, truth: Pose2D, t: float = 0.0) -> dict[int, np.ndarray]:
        return detect_markers(
            self.markers,
            truth,
            self.intrinsics,
            self.mount,
            self.world,
            self.params,
            self.rng,
            t,
            self.miss_rate,
        )
