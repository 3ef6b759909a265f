"""A storey as the renderer sees it: vertical wall surfaces, feature panels, decorations, clutter.

Walls are vertical, so the whole scene is 2D line segments with a height range: the wall
outline of the BIM obstacles (floor to ceiling), the features of ``features.csv`` as rectangles
on those walls (class, width, height), unlabelled wall decorations (posters, lift call panels,
exit signs) and free-standing clutter boxes with a height (material stacks, people).

Segments are oriented so that free space lies on their right: the unit normal ``(dy, -dx)``
points from the wall into the room.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import shapely
from shapely.geometry import LineString, MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from bimkit.errors import InputError
from bimtools.site.load import StoreyModel
from initcli.core.features.classes import ClassMap
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.detector import CLASS_NAMES

__all__ = [
    "CLUTTER_BOX",
    "CLUTTER_PERSON",
    "Camera",
    "Clutter",
    "DECOR_CABINET",
    "DECOR_CALL_PANEL",
    "DECOR_EXIT_SIGN",
    "DECOR_INDICATOR",
    "DECOR_POSTER",
    "DECOR_SWITCH",
    "DECOR_WINDOW",
    "Panels",
    "Scene",
    "SceneFeature",
    "camera_pose_in_world",
    "panels_from_rows",
    "standard_decorations",
    "wall_line",
]

# Decoration kinds (unlabelled things on walls).
DECOR_POSTER = 0
DECOR_CALL_PANEL = 1
DECOR_INDICATOR = 2
DECOR_EXIT_SIGN = 3
DECOR_CABINET = 4
DECOR_WINDOW = 5
DECOR_SWITCH = 6

# Clutter kinds.
CLUTTER_BOX = 0
CLUTTER_PERSON = 1


@dataclass(frozen=True)
class Camera:
    """Pinhole camera with zero pitch and roll at ``z`` metres above the floor (walls stay vertical)."""

    fx: float = 160.0
    fy: float = 160.0
    cx: float = 160.0
    cy: float = 120.0
    width: int = 320
    height: int = 240
    z: float = 1.0
    max_range: float = 40.0

    @staticmethod
    def from_fov(width: int = 320, height: int = 240, hfov_deg: float = 90.0, z: float = 1.0) -> Camera:
        f = 0.5 * width / math.tan(math.radians(hfov_deg) / 2.0)
        return Camera(f, f, width / 2.0, height / 2.0, int(width), int(height), z)

    @staticmethod
    def from_intrinsics(intrinsics: CameraIntrinsics, z: float = 1.0, max_range: float = 40.0) -> Camera:
        i = intrinsics
        return Camera(i.fx, i.fy, i.cx, i.cy, int(i.width), int(i.height), z, max_range)

    def intrinsics(self) -> CameraIntrinsics:
        return CameraIntrinsics(self.fx, self.fy, self.cx, self.cy, self.width, self.height)


def camera_pose_in_world(
    robot_xy_yaw: tuple[float, float, float], mount: CameraMount
) -> tuple[float, float, float]:
    """The camera's (x, y, yaw) in the world from the robot's pose and its mount (pitch, roll ignored)."""
    x, y, yaw = robot_xy_yaw
    c, s = math.cos(yaw), math.sin(yaw)
    return (x + c * mount.x - s * mount.y, y + s * mount.x + c * mount.y, yaw + mount.yaw)


@dataclass(frozen=True)
class SceneFeature:
    """One labelled element: a rectangle on a wall, ``normal`` towards the side it is seen from."""

    id: str
    category: str
    class_name: str
    class_index: int
    x: float
    y: float
    normal: tuple[float, float]
    width: float
    height: float


@dataclass
class Panels:
    """Rectangles on walls (arrays of length P): centre, normal, half width, bottom and top height."""

    centre: np.ndarray  # (P, 2)
    normal: np.ndarray  # (P, 2)
    half_width: np.ndarray  # (P,)
    bottom: np.ndarray  # (P,)
    top: np.ndarray  # (P,)
    kind: np.ndarray  # (P,) int
    rgb: np.ndarray  # (P, 3) float 0-255

    @staticmethod
    def empty() -> Panels:
        return Panels(
            np.zeros((0, 2)),
            np.zeros((0, 2)),
            np.zeros(0),
            np.zeros(0),
            np.zeros(0),
            np.zeros(0, dtype=int),
            np.zeros((0, 3)),
        )

    def __len__(self) -> int:
        return len(self.half_width)

    @property
    def tangent(self) -> np.ndarray:
        """Unit vector to the right of a viewer facing the panel."""
        return np.column_stack([-self.normal[:, 1], self.normal[:, 0]])

    def concat(self, other: Panels) -> Panels:
        return Panels(
            *(
                np.concatenate([getattr(self, k), getattr(other, k)])
                for k in ("centre", "normal", "half_width", "bottom", "top", "kind", "rgb")
            )
        )


@dataclass
class Clutter:
    """Free-standing boxes: segments with an object id, the object's top height, kind and colour."""

    segments: np.ndarray  # (C, 4)
    obj: np.ndarray  # (C,) object index
    top: np.ndarray  # (O,)
    kind: np.ndarray  # (O,) int
    rgb: np.ndarray  # (O, 3)

    @staticmethod
    def empty() -> Clutter:
        return Clutter(
            np.zeros((0, 4)), np.zeros(0, dtype=int), np.zeros(0), np.zeros(0, dtype=int), np.zeros((0, 3))
        )

    @staticmethod
    def from_boxes(
        boxes: list[tuple[float, float, float, float, float]],
        tops: list[float],
        kinds: list[int] | None = None,
        rgb: np.ndarray | None = None,
    ) -> Clutter:
        """Boxes ``(cx, cy, half_length, half_width, yaw)`` with heights -> clutter segments."""
        if not boxes:
            return Clutter.empty()
        segs, obj = [], []
        for i, (cx, cy, hl, hw, yaw) in enumerate(boxes):
            c, s = math.cos(yaw), math.sin(yaw)
            corners = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw], [-hl, -hw]])
            ring = corners @ np.array([[c, s], [-s, c]]) + [cx, cy]
            segs.append(np.column_stack([ring[:-1], ring[1:]]))
            obj += [i] * 4
        n = len(boxes)
        colours = rgb if rgb is not None else np.tile([150.0, 120.0, 90.0], (n, 1))
        return Clutter(
            np.concatenate(segs),
            np.array(obj),
            np.asarray(tops, dtype=float),
            np.asarray(kinds if kinds is not None else [CLUTTER_BOX] * n),
            np.asarray(colours, float),
        )

    @staticmethod
    def from_rings(
        rings: list[np.ndarray],
        tops: list[float],
        kinds: list[int] | None = None,
        rgb: np.ndarray | None = None,
    ) -> Clutter:
        """Closed footprints ((n, 2) rings, first point repeated) with heights -> clutter segments."""
        if not rings:
            return Clutter.empty()
        segs, obj = [], []
        for i, ring in enumerate(rings):
            r = np.asarray(ring, dtype=float)
            if len(r) > 2 and not np.allclose(r[0], r[-1]):
                r = np.vstack([r, r[:1]])
            area2 = float(np.sum(r[:-1, 0] * r[1:, 1] - r[1:, 0] * r[:-1, 1]))
            if area2 < 0:  # counter-clockwise: free space on the right of every edge
                r = r[::-1]
            segs.append(np.column_stack([r[:-1], r[1:]]))
            obj += [i] * (len(r) - 1)
        n = len(rings)
        colours = rgb if rgb is not None else np.tile([150.0, 120.0, 90.0], (n, 1))
        kinds = kinds if kinds is not None else [CLUTTER_BOX] * n
        return Clutter(
            np.concatenate(segs),
            np.array(obj),
            np.asarray(tops, dtype=float),
            np.asarray(kinds),
            np.asarray(colours, float),
        )

    @property
    def count(self) -> int:
        return len(self.top)


@dataclass
class Scene:
    """Everything the raycaster needs for one storey."""

    walls: np.ndarray  # (S, 4) x1 y1 x2 y2, free space on the right unless two_sided
    two_sided: np.ndarray  # (S,) bool
    wall_offset: np.ndarray  # (S,) texture coordinate of each segment's start, metres
    features: list[SceneFeature]
    class_names: tuple[str, ...] = CLASS_NAMES
    ceiling: float = 3.0
    decorations: Panels = field(default_factory=Panels.empty)
    clutter: Clutter = field(default_factory=Clutter.empty)
    footprint: Polygon | MultiPolygon | None = None  # the union of the obstacles (solid)
    name: str = ""

    def __post_init__(self) -> None:
        f = self.features
        self.feature_panels = Panels(
            centre=np.array([[a.x, a.y] for a in f], dtype=float).reshape(-1, 2),
            normal=np.array([a.normal for a in f], dtype=float).reshape(-1, 2),
            half_width=np.array([a.width / 2.0 for a in f], dtype=float),
            bottom=np.zeros(len(f)),
            top=np.array([a.height for a in f], dtype=float),
            kind=np.array([a.class_index for a in f], dtype=int),
            rgb=np.zeros((len(f), 3)),
        )

    def with_extras(
        self, decorations: Panels | None = None, clutter: Clutter | None = None, ceiling: float | None = None
    ) -> Scene:
        """A copy with other decorations, clutter or ceiling height (the walls are shared)."""
        return replace(
            self,
            decorations=self.decorations if decorations is None else decorations,
            clutter=self.clutter if clutter is None else clutter,
            ceiling=self.ceiling if ceiling is None else ceiling,
        )

    @staticmethod
    def from_storey(
        storey: StoreyModel,
        class_names: tuple[str, ...] = CLASS_NAMES,
        class_map: ClassMap | None = None,
        ceiling: float = 3.0,
        decorate: bool = True,
    ) -> Scene:
        """Walls from the storey's obstacle footprints (or its wall surfaces), features by class.

        Features whose category is not one of ``class_names`` (after ``class_map``) are left out.
        With ``decorate``, lifts get a call panel and floor indicator and stairs an exit sign.
        """
        footprint, walls, two_sided = _storey_walls(storey)
        feats = _scene_features(storey, class_names, class_map or ClassMap())
        # Real models' section cuts leave the door openings open: close each feature's opening with a
        # two-sided segment in its plane, so that rays stop on the feature (it is drawn there) and the
        # circulation area does not leak through an entrance to the outside. Behind a closed wall
        # surface the segment is hidden and changes nothing.
        if feats:
            closing = np.array(
                [
                    [
                        f.x - f.normal[1] * f.width / 2,
                        f.y + f.normal[0] * f.width / 2,
                        f.x + f.normal[1] * f.width / 2,
                        f.y - f.normal[0] * f.width / 2,
                    ]
                    for f in feats
                ]
            )
            walls = np.vstack([walls.reshape(-1, 4), closing])
            two_sided = np.concatenate([two_sided, np.ones(len(closing), dtype=bool)])
        lengths = np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1])
        offset = np.concatenate([[0.0], np.cumsum(lengths)[:-1]]) if len(walls) else np.zeros(0)
        scene = Scene(
            walls,
            two_sided,
            offset,
            feats,
            tuple(class_names),
            ceiling,
            footprint=footprint,
            name=storey.name,
        )
        if decorate:
            scene.decorations = standard_decorations(scene)
        return scene


def _storey_walls(storey: StoreyModel) -> tuple[Polygon | MultiPolygon | None, np.ndarray, np.ndarray]:
    """The union of the storey's obstacle footprints (None without obstacles) and the wall segments
    to render: the footprint's outline, else the storey's wall surfaces (two-sided)."""
    polys = []
    for o in storey.obstacles:
        try:
            p = Polygon(o.exterior, o.holes)
        except (ValueError, TypeError):
            continue
        if not p.is_valid:
            p = p.buffer(0)
        if not p.is_empty and p.area > 1e-6:
            polys.append(p)
    if polys:
        footprint = (
            shapely.unary_union(polys).buffer(0.002, join_style="mitre").buffer(-0.002, join_style="mitre")
        )
        walls, two_sided = _outline_segments(footprint)
        return footprint, walls, two_sided
    if storey.walls:
        walls = np.array([[w.x1, w.y1, w.x2, w.y2] for w in storey.walls], dtype=float)
        return None, walls, np.ones(len(walls), dtype=bool)
    raise InputError(f"storey {storey.name!r}: no walls or obstacles to render (walls.geojson missing?)")


def _scene_features(storey: StoreyModel, class_names: tuple[str, ...], cmap: ClassMap) -> list[SceneFeature]:
    """The storey's features whose category (after ``cmap``) is one of ``class_names``; unit normals,
    at least 0.3 m wide and 0.5 m tall."""
    index = {c: i for i, c in enumerate(class_names)}
    feats = []
    for f in storey.features:
        cls = cmap.canonical(f.category)
        if cls not in index:
            continue
        n = math.hypot(f.norm_x, f.norm_y) or 1.0
        feats.append(
            SceneFeature(
                f.id,
                f.category,
                cls,
                index[cls],
                f.x,
                f.y,
                (f.norm_x / n, f.norm_y / n),
                max(f.width, 0.3),
                max(f.height, 0.5),
            )
        )
    return feats


def _outline_segments(geom: Polygon | MultiPolygon) -> tuple[np.ndarray, np.ndarray]:
    parts = list(geom.geoms) if hasattr(geom, "geoms") else [geom]
    segs = []
    for p in parts:
        if not isinstance(p, Polygon) or p.is_empty:
            continue
        p = orient(p.simplify(0.004), sign=1.0)  # exterior CCW, holes CW: free space on the right
        for ring in [p.exterior, *p.interiors]:
            xy = np.asarray(ring.coords)
            seg = np.column_stack([xy[:-1], xy[1:]])
            keep = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) > 1e-4
            segs.append(seg[keep])
    walls = np.concatenate(segs) if segs else np.zeros((0, 4))
    return walls, np.zeros(len(walls), dtype=bool)


def standard_decorations(scene: Scene, rng: np.random.Generator | None = None) -> Panels:
    """Lift call panels and floor indicators, exit signs over stair entrances (fixed or random)."""
    rows: list[tuple] = []
    for f in scene.features:
        n = np.array(f.normal)
        t = np.array([-n[1], n[0]])
        c = np.array([f.x, f.y])
        if f.class_name == "lift":
            side = 1.0 if rng is None or rng.random() < 0.5 else -1.0
            off = f.width / 2 + (0.25 if rng is None else rng.uniform(0.15, 0.4))
            rows.append((c + side * off * t, n, 0.05, 0.95, 1.3, DECOR_CALL_PANEL, (170, 170, 175)))
            if rng is None or rng.random() < 0.7:
                rows.append((c, n, 0.2, f.height + 0.12, f.height + 0.3, DECOR_INDICATOR, (25, 25, 30)))
        elif f.class_name == "stairs" and (rng is None or rng.random() < 0.7):
            rows.append((c, n, 0.18, f.height + 0.1, f.height + 0.3, DECOR_EXIT_SIGN, (20, 150, 60)))
    return panels_from_rows(rows)


def panels_from_rows(rows: list[tuple]) -> Panels:
    """Rows ``(centre, normal, half_width, bottom, top, kind, rgb)`` -> :class:`Panels`."""
    if not rows:
        return Panels.empty()
    return Panels(
        centre=np.array([r[0] for r in rows], dtype=float),
        normal=np.array([r[1] for r in rows], dtype=float),
        half_width=np.array([r[2] for r in rows], dtype=float),
        bottom=np.array([r[3] for r in rows], dtype=float),
        top=np.array([r[4] for r in rows], dtype=float),
        kind=np.array([r[5] for r in rows], dtype=int),
        rgb=np.array([r[6] for r in rows], dtype=float),
    )


def wall_line(scene: Scene) -> list[LineString]:
    """The wall segments as shapely lines (for plots and placement checks)."""
    return [LineString([(s[0], s[1]), (s[2], s[3])]) for s in scene.walls]
