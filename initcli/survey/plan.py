"""The start samples of a storey's survey: its settings, and the storey precomputed (features,
occluding edges, wall-following loops and what the camera sees along them, the starts, the spaces a
start fails in)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bimtools.site.load import StoreyModel
from initcli.config.building import self_similar
from initcli.core.features.classes import ClassMap
from initcli.core.features.visibility import CameraModel, FeatureArrays, visible
from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
from initcli.core.lidar.registration import RegistrationMap
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.symmetry import Turn
from initcli.core.verify.params import VerificationParams
from initcli.storey.circulation import Circulation
from initcli.storey.doors import closed_doors, door_ids
from initcli.storey.outlines import polygon_edges
from initcli.survey.exploration import Loop, follow_loops
from initcli.survey.lidar import LidarModel
from initcli.survey.spaces import LidarTwin, ShutInRoom, lidar_twin_spaces, shut_in_rooms
from initcli.survey.uniqueness import UniquenessParams
from initcli.verify.registration import storey_registration_map

__all__ = [
    "FACED_BY",
    "StoreyPlan",
    "SurveyParams",
    "cumulative_sightings",
    "occluders_of",
    "plan_storey",
    "storey_features",
]

FACED_BY = 1  # features facing a closed-door region that make it circulation area (rooms: none)


@dataclass(frozen=True)
class SurveyParams:
    """Every setting of the survey with its one default (the session's defaults where they exist)."""

    spacing: float = 1.0  # m between sample positions
    headings: int = 4  # start headings per position
    limit_m: float = 150.0  # m driven without a unique match: never unique (paper §4.3)
    step_m: float = 0.1  # m between images along the path (0.5 m/s at 5 Hz)
    look_step: float = 0.12  # rad between images of the look round (0.6 rad/s at 5 Hz)
    initial_look: bool = True  # turn once on the spot first, as the session does
    wall_distance: float = 0.7  # m kept to the followed wall
    side: int = 1  # +1 left wall, -1 right wall
    start_clearance: float = 0.6  # m from the nearest obstacle for a start (as random starts)
    min_sightings: int = 3  # images before a feature is confirmed (detection filter)
    # m: walls this close count as alike for the lidar twins (the session's verification.scan_tolerance)
    scan_tolerance: float = field(default_factory=lambda: VerificationParams().scan_tolerance)
    camera: CameraModel = field(default_factory=lambda: CameraModel(DEFAULT_CAMERA, DEFAULT_MOUNT))
    matching: UniquenessParams = field(default_factory=UniquenessParams)
    landmark_spacing: float = 4.0  # m between candidate landmark positions along a corridor wall
    landmark_candidates: int = 30  # candidates tried at most per landmark
    landmark_stride: int = 4  # candidates are scored on every n-th start, the chosen one on all
    camera_on: bool = True  # false: the robot's camera sees nothing (absent, or every image missed)
    # the session's lidar registration along the loops (enabled: false, the camera alone: the paper)
    registration: RegistrationParams = field(default_factory=RegistrationParams)
    lidar: LidarModel = field(default_factory=LidarModel)


@dataclass
class StoreyPlan:
    """One storey, precomputed: features, occluders, loops, what the loops see, the start samples."""

    name: str
    features: FeatureArrays
    occluders: np.ndarray  # (W, 4) wall and obstacle edges
    walls: np.ndarray  # (V, 6) wall surfaces x1 y1 x2 y2 nx ny (landmark candidates)
    circulation: Circulation
    loops: list[Loop]
    loop_cum: list[np.ndarray]  # per loop (2P + 1, F): images showing each feature along two laps
    starts: np.ndarray  # (S, 3) x, y, yaw
    position: np.ndarray  # (S,) index of the start's position
    positions: np.ndarray  # (M, 2)
    shut_in: list[ShutInRoom] = field(default_factory=list)
    shut_in_cells: np.ndarray | None = None  # bool mask over the grid: where shut_in rooms lie
    twin: Turn | None = None  # the turn that maps the storey onto itself: no start initialises
    lidar_twins: list[LidarTwin] = field(default_factory=list)
    lidar_twin_cells: np.ndarray | None = None  # bool mask over the grid: where lidar_twins lie
    scan_segments: np.ndarray | None = None  # (W, 4) what a scan sees: occluders and closed door leaves
    registration_map: RegistrationMap | None = None  # the storey's map as the registration reads it
    # the lidar's placed loop points, once per settings (initcli.survey.run.lidar_along): the loops
    # do not change when the starts do (an evaluation's own starts surveyed after the survey's)
    lidar_placed: dict[tuple[object, ...], list[np.ndarray]] = field(default_factory=dict)

    @property
    def lidar_twin_start_share(self) -> float:
        """Share of the start positions in a space with a lidar twin (camera off: none initialises)."""
        if not len(self.positions):
            return 0.0
        return float(np.mean(self.in_lidar_twin(self.positions)))

    def in_lidar_twin(self, xy: np.ndarray) -> np.ndarray:
        """(N,) bool: which of the points ``xy`` (N, 2) lie in a space with a lidar twin."""
        cells = self.lidar_twin_cells
        found = np.zeros(len(xy), dtype=bool)
        if cells is None:
            return found
        row, col = self.circulation.grid.world_to_cell(xy[:, 0], xy[:, 1])
        inside = (row >= 0) & (row < cells.shape[0]) & (col >= 0) & (col < cells.shape[1])
        found[inside] = cells[row[inside], col[inside]]
        return found


def storey_features(storey: StoreyModel, cmap: ClassMap | None = None) -> FeatureArrays:
    cmap = cmap or ClassMap()
    f = storey.features
    return FeatureArrays(
        np.array([[x.x, x.y] for x in f], dtype=float).reshape(-1, 2),
        np.array([[x.norm_x, x.norm_y] for x in f], dtype=float).reshape(-1, 2),
        np.array([x.height for x in f], dtype=float),
        tuple(cmap.canonical(x.category) for x in f),
    )


def occluders_of(storey: StoreyModel) -> np.ndarray:
    """What hides a feature: the obstacle outlines (as the simulator's world), else the wall surfaces."""
    parts = [polygon_edges(np.asarray(o.exterior)) for o in storey.obstacles]
    parts += [polygon_edges(np.asarray(h)) for o in storey.obstacles for h in o.holes]
    if not parts:
        parts = [np.array([[w.x1, w.y1, w.x2, w.y2] for w in storey.walls], dtype=float).reshape(-1, 4)]
    return np.concatenate(parts).reshape(-1, 4)


def cumulative_sightings(vis: np.ndarray) -> np.ndarray:
    """(P, F) images showing each feature along a loop -> (2P + 1, F) their running count over two laps."""
    twice = np.vstack([vis, vis]).astype(np.int32)
    return np.vstack([np.zeros((1, vis.shape[1]), dtype=np.int32), np.cumsum(twice, axis=0, dtype=np.int32)])


def plan_storey(storey: StoreyModel, params: SurveyParams, cmap: ClassMap | None = None) -> StoreyPlan:
    """Precompute a storey; raises ValueError when it has no occupancy map.

    The starts and wall-following loops lie in the circulation area with every door leaf closed, as
    the simulated world has them: the map leaves door openings free, and a room behind a door is
    not where a session starts or drives. Every region that FACED_BY features face from the
    front is surveyed (each corridor section between closed doors; ``bim-init eval`` draws its
    starts in the one most features face)."""
    leaves = closed_doors(storey.features, door_ids(storey.features))
    circulation = Circulation.of(storey, closed=leaves, min_votes=FACED_BY)
    grid = circulation.grid
    features = storey_features(storey, cmap)
    occluders = occluders_of(storey)
    loops = follow_loops(
        circulation.label, circulation.clearance, grid, params.wall_distance, params.side, params.step_m
    )
    loop_cum = [cumulative_sightings(visible(lp.poses, features, occluders, params.camera)) for lp in loops]
    k = max(1, round(params.spacing / grid.resolution))
    rows, cols = np.nonzero(circulation.label & (circulation.clearance >= params.start_clearance))
    # one start per spacing x spacing block of the start region: its cell nearest the block centre
    block = (rows // k) * (circulation.label.shape[1] // k + 1) + cols // k
    off = np.hypot(rows % k - (k - 1) / 2, cols % k - (k - 1) / 2)
    order = np.lexsort((off, block))
    first = order[np.r_[True, block[order][1:] != block[order][:-1]]] if len(order) else order
    x, y = grid.cell_centre(rows[first], cols[first])
    positions = np.column_stack([x, y]).astype(float).reshape(-1, 2)
    yaws = np.arange(params.headings) * (2 * math.pi / params.headings)
    starts = np.column_stack(
        [np.repeat(positions, params.headings, axis=0), np.tile(yaws, len(positions))]
    ).reshape(-1, 3)
    position = np.repeat(np.arange(len(positions)), params.headings)
    walls = np.array([[w.x1, w.y1, w.x2, w.y2, *w.normal] for w in storey.walls], dtype=float).reshape(-1, 6)
    rooms, cells = shut_in_rooms(circulation, params.start_clearance)
    twins, twin_cells = lidar_twin_spaces(circulation, params.start_clearance, params.scan_tolerance)
    return StoreyPlan(
        storey.name,
        features,
        occluders,
        walls,
        circulation,
        loops,
        loop_cum,
        starts,
        position,
        positions,
        rooms,
        cells,
        self_similar(storey),
        twins,
        twin_cells,
        np.concatenate([occluders, *(polygon_edges(np.asarray(leaf.exterior)) for leaf in leaves)]),
        storey_registration_map(storey.name, storey, cmap or ClassMap())
        if params.registration.enabled
        else None,
    )
