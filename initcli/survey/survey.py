"""The survey of one storey: start samples, their feature sequences, the distance to a unique match.

Pure parts on arrays (no files, no terminal): :func:`plan_storey` precomputes the storey (features,
occluding edges, wall-following loops and what the camera sees along them), :func:`sample_views`
what each start sees during its look round and its approach to a loop, :func:`sequences` the order
in which features get confirmed (after ``min_sightings`` images, as the detection filter does) and
at what distance, :func:`survey_storey` runs the matching on an executor, :func:`summarise` gives
the numbers of ``survey.json`` and :func:`suggest_landmarks` the greedy landmark placement.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from bimtools.site.load import StoreyModel
from initcli.config.building import self_similar
from initcli.core.features.classes import ClassMap
from initcli.core.features.visibility import CameraModel, FeatureArrays, visible
from initcli.core.lidar.region_twins import IDENTITY_M, RegionTwin, moved, region_twins
from initcli.core.lidar.symmetry import Turn
from initcli.core.verify.params import VerificationParams
from initcli.executor import Executor, LocalExecutor, map_unordered
from initcli.sim.as_built import closed_doors, door_ids
from initcli.sim.scenario import Circulation
from initcli.sim.synthetic_log import DEFAULT_CAMERA, DEFAULT_MOUNT, sim_features_from_bim
from initcli.sim.world import polygon_edges
from initcli.survey.exploration import Entry, Loop, follow_loops, join_loop, look_round
from initcli.survey.uniqueness import UniquenessParams, first_unique

__all__ = [
    "FACED_BY",
    "LANDMARK_CLASS",
    "LANDMARK_HEIGHT",
    "Landmark",
    "LidarTwin",
    "SHUT_IN_MIN_AREA",
    "SampleViews",
    "ShutInRoom",
    "StoreyPlan",
    "StoreySurvey",
    "SurveyParams",
    "UNIQUE_WITHIN",
    "landmark_candidates",
    "occluders_of",
    "plan_storey",
    "sample_views",
    "sequences",
    "storey_features",
    "suggest_landmarks",
    "summarise",
    "survey_storey",
    "unique_distances",
    "with_feature",
]

LANDMARK_CLASS = "landmark"  # each suggested landmark gets its own category: landmark_1, landmark_2
LANDMARK_HEIGHT = 2.0  # m: a sign whose centre is at the camera's height
UNIQUE_WITHIN = (5.0, 10.0, 20.0)  # m: the shares of survey.json
FACED_BY = 1  # features facing a closed-door region that make it circulation area (rooms: none)
SHUT_IN_MIN_AREA = 2.0  # m²: a closed-off space at least this large where a robot can stand is marked
SHUT_IN_LABEL = "cannot initialise from here"  # what the map says over a shut-in room


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


@dataclass(frozen=True)
class ShutInRoom:
    """A space closed off by the doors (every leaf closed) that no feature faces: a robot that
    starts there goes round it and stops shut in (the session's ``reason: shut in``)."""

    x: float  # m: a cell of the room where a robot can stand, nearest its centroid
    y: float
    area_m2: float  # where a robot can stand (the start clearance)


@dataclass(frozen=True)
class LidarTwin:
    """A space (every door leaf closed) that a turn or shift lays on itself or on another space, walls
    on walls and floor on floor (:mod:`initcli.core.lidar.region_twins`): with the camera off a lidar
    sees a pose there and its twin alike (within the session's scan tolerance), and a start there
    initialises only by a chance difference while the doors stay shut."""

    x: float  # m: a cell of the space where a robot can stand, nearest its centroid
    y: float
    area_m2: float  # where a robot can stand (the start clearance)
    twin_x: float  # m: where the lidar sees the same as at (x, y) ...
    twin_y: float
    turn_deg: float  # ... turned this much
    start_region: bool  # part of the surveyed start region (else a shut-in room)


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

    @property
    def lidar_twin_start_share(self) -> float:
        """Share of the start positions in a space with a lidar twin (camera off: none initialises)."""
        cells = self.lidar_twin_cells
        if cells is None or not len(self.positions):
            return 0.0
        row, col = self.circulation.grid.world_to_cell(self.positions[:, 0], self.positions[:, 1])
        return float(np.mean(cells[row, col]))


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


def _cumulative(vis: np.ndarray) -> np.ndarray:
    twice = np.vstack([vis, vis]).astype(np.int32)
    return np.vstack([np.zeros((1, vis.shape[1]), dtype=np.int32), np.cumsum(twice, axis=0, dtype=np.int32)])


def plan_storey(storey: StoreyModel, params: SurveyParams, cmap: ClassMap | None = None) -> StoreyPlan:
    """Precompute a storey; raises ValueError when it has no occupancy map.

    The starts and wall-following loops lie in the circulation area with every door leaf closed, as
    the simulated world has them: the map leaves door openings free, and a room behind a door is
    not where a session starts or drives. Every region that FACED_BY features face from the
    front is surveyed (each corridor section between closed doors; ``bim-init eval`` draws its
    starts in the one most features face)."""
    leaves = closed_doors(sim_features_from_bim(storey.features, cmap), door_ids(storey.features))
    circulation = Circulation.of(storey, closed=leaves, min_votes=FACED_BY)
    grid = circulation.grid
    features = storey_features(storey, cmap)
    occluders = occluders_of(storey)
    loops = follow_loops(
        circulation.label, circulation.clearance, grid, params.wall_distance, params.side, params.step_m
    )
    loop_cum = [_cumulative(visible(lp.poses, features, occluders, params.camera)) for lp in loops]
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
    )


def _standing(circulation: Circulation, clearance: float, where: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The labels of the connected free regions with cells in ``where`` that have at least
    SHUT_IN_MIN_AREA where a robot can stand (``clearance`` m from the nearest obstacle), and the
    mask of those standing cells."""
    regions = circulation.regions
    if regions is None:
        return np.zeros(0, dtype=int), np.zeros(circulation.label.shape, dtype=bool)
    stand = (regions > 0) & where & (circulation.clearance >= clearance)
    counts = np.bincount(regions[stand], minlength=int(regions.max()) + 1)
    keep = np.flatnonzero(counts * circulation.grid.resolution**2 >= SHUT_IN_MIN_AREA)
    keep = keep[keep > 0]
    return keep, stand & np.isin(regions, keep)


def _nearest_centroid(circulation: Circulation, mask: np.ndarray) -> tuple[float, float]:
    """The centre of the cell of ``mask`` nearest its centroid (m)."""
    rows, cols = np.nonzero(mask)
    k = int(np.argmin(np.hypot(rows - rows.mean(), cols - cols.mean())))
    x, y = circulation.grid.cell_centre(rows[k : k + 1], cols[k : k + 1])
    return round(float(x[0]), 2), round(float(y[0]), 2)


def shut_in_rooms(circulation: Circulation, clearance: float) -> tuple[list[ShutInRoom], np.ndarray]:
    """The connected free regions outside the surveyed ``circulation`` (every door leaf closed; no
    feature faces them) with at least SHUT_IN_MIN_AREA where a robot can stand (``clearance`` m from
    the nearest obstacle), and the mask of their cells."""
    keep, cells = _standing(circulation, clearance, ~circulation.label)
    cell = circulation.grid.resolution**2
    rooms: list[ShutInRoom] = []
    for label in keep:
        room = cells & (circulation.regions == label)
        rooms.append(ShutInRoom(*_nearest_centroid(circulation, room), round(float(room.sum() * cell), 1)))
    return rooms, cells


def _farthest_from_fixed_point(
    circulation: Circulation, mask: np.ndarray, twin: RegionTwin
) -> tuple[float, float]:
    """The standing cell of ``mask`` that the twin's motion moves farthest (m): a point whose twin
    is another place, where the space's own centre is the centre of its turn."""
    rows, cols = np.nonzero(mask)
    x, y = circulation.grid.cell_centre(rows, cols)
    xy = np.column_stack([x, y])
    k = int(np.argmax(moved(twin.motion, xy)))
    return round(float(xy[k, 0]), 2), round(float(xy[k, 1]), 2)


def lidar_twin_spaces(
    circulation: Circulation, clearance: float, tolerance: float
) -> tuple[list[LidarTwin], np.ndarray]:
    """The spaces of the map (every door leaf closed; start region and shut-in rooms, at least
    SHUT_IN_MIN_AREA where a robot can stand) that have a lidar twin, walls alike within
    ``tolerance`` m, and the mask of their cells."""
    keep, cells = _standing(circulation, clearance, np.ones(circulation.label.shape, dtype=bool))
    regions = circulation.regions
    if regions is None or not len(keep):
        return [], cells  # no space where a robot can stand: an empty mask
    grid = circulation.grid
    twins = region_twins(regions, grid.resolution, (grid.origin[0], grid.origin[1]), keep, tolerance)
    out: list[LidarTwin] = []
    mask = np.zeros(regions.shape, dtype=bool)
    for twin in twins:
        space = cells & (regions == twin.label)
        x, y = _nearest_centroid(circulation, space)
        if moved(twin.motion, np.array([x, y]))[0] < IDENTITY_M:
            x, y = _farthest_from_fixed_point(circulation, space, twin)  # the centre of a half turn
        tx, ty = twin.motion.apply(np.array([x, y]))
        start = bool((space & circulation.label).any())
        area = round(float(space.sum() * grid.resolution**2), 1)
        turn = round(twin.turn_deg, 1) + 0.0  # round(-0.04) is -0.0
        out.append(LidarTwin(x, y, area, round(float(tx), 2), round(float(ty), 2), turn, start))
        mask |= space
    return out, mask


@dataclass
class SampleViews:
    """What every start sees before it reaches its loop, and where it joins the loop."""

    look: np.ndarray  # (S, K, F) images of the look round
    approach: list[np.ndarray]  # per start (A, F) images of the approach
    entries: list[Entry | None]


def _look_poses(plan: StoreyPlan, params: SurveyParams) -> np.ndarray:
    if not params.initial_look:
        return plan.starts[:, None, :]
    return np.stack([look_round(s, params.look_step) for s in plan.starts])


def sample_views(plan: StoreyPlan, params: SurveyParams) -> SampleViews:
    looks = _look_poses(plan, params)
    s, k = looks.shape[:2]
    look = visible(looks.reshape(-1, 3), plan.features, plan.occluders, params.camera).reshape(s, k, -1)
    entries = [join_loop(st, plan.loops, plan.occluders, params.side, params.step_m) for st in plan.starts]
    approach_poses = [e.approach if e is not None else np.zeros((0, 3)) for e in entries]
    flat = visible(np.concatenate(approach_poses), plan.features, plan.occluders, params.camera)
    bounds = np.cumsum([0] + [len(a) for a in approach_poses])
    approach = [flat[bounds[i] : bounds[i + 1]] for i in range(len(entries))]
    return SampleViews(look, approach, entries)


def with_feature(
    plan: StoreyPlan, views: SampleViews, params: SurveyParams, extra: FeatureArrays
) -> tuple[StoreyPlan, SampleViews]:
    """The plan and views with the features of ``extra`` appended (a suggested landmark)."""
    features = FeatureArrays(
        np.vstack([plan.features.xy, extra.xy]),
        np.vstack([plan.features.normal, extra.normal]),
        np.concatenate([plan.features.height, extra.height]),
        (*plan.features.cls, *extra.cls),
    )
    cum = [
        np.hstack([c, _cumulative(visible(lp.poses, extra, plan.occluders, params.camera))])
        for lp, c in zip(plan.loops, plan.loop_cum, strict=True)
    ]
    looks = _look_poses(plan, params)
    s, k = looks.shape[:2]
    look_extra = visible(looks.reshape(-1, 3), extra, plan.occluders, params.camera).reshape(s, k, -1)
    sizes = [len(a) for a in views.approach]
    poses = np.concatenate([e.approach if e is not None else np.zeros((0, 3)) for e in views.entries])
    flat = visible(poses, extra, plan.occluders, params.camera)
    bounds = np.cumsum([0, *sizes])
    approach = [np.hstack([a, flat[bounds[i] : bounds[i + 1]]]) for i, a in enumerate(views.approach)]
    # The landmark is for the camera: the walls, and so the lidar's twins, stay; the turn of a
    # self-similar storey is not looked for again (a sign on one side breaks it).
    new_plan = dataclasses.replace(plan, features=features, loop_cum=cum, twin=None)
    return new_plan, SampleViews(np.concatenate([views.look, look_extra], axis=2), approach, views.entries)


def sequences(
    plan: StoreyPlan, views: SampleViews, params: SurveyParams, which: Iterable[int] | None = None
) -> tuple[list[tuple[int, ...]], list[np.ndarray]]:
    """Per start (of ``which``, default all): the feature indices in the order they are confirmed,
    and the distance (m) driven when each is (features confirmed beyond ``limit_m`` are left out)."""
    need0 = params.min_sightings
    out_seq: list[tuple[int, ...]] = []
    out_dist: list[np.ndarray] = []
    n_f = len(plan.features)
    for i in range(len(plan.starts)) if which is None else which:
        when = np.full(n_f, np.inf)
        order = np.full(n_f, np.inf)
        counts = np.cumsum(views.look[i], axis=0)
        hit = counts >= need0
        got = np.asarray(hit.any(axis=0))  # an array (numpy's stubs say: or a scalar)
        when[got] = 0.0
        order[got] = hit.argmax(axis=0)[got]
        seen = counts[-1] if len(counts) else np.zeros(n_f, dtype=int)
        entry = views.entries[i]
        if entry is not None and len(views.approach[i]):
            a = views.approach[i]
            ca = seen[None, :] + np.cumsum(a, axis=0)
            hit = (ca >= need0) & ~got[None, :]
            new = hit.any(axis=0)
            step = entry.length / len(a)
            first = hit.argmax(axis=0)
            when[new] = (first[new] + 1) * step
            order[new] = 1e6 + first[new]
            got |= new
            seen = ca[-1]
        if entry is not None:
            cum = plan.loop_cum[entry.loop]
            p = len(plan.loops[entry.loop])
            e = entry.index
            need = need0 - np.minimum(seen, need0)
            lap = min(p, int((params.limit_m - entry.length) / params.step_m) + 1)
            for f in np.flatnonzero(~got):
                j = int(np.searchsorted(cum[:, f], cum[e, f] + need[f], side="left"))
                if j - 1 - e < lap and j > e:
                    when[f] = entry.length + (j - 1 - e) * params.step_m
                    order[f] = 2e6 + (j - 1 - e)
        keep = np.flatnonzero(np.isfinite(when) & (when <= params.limit_m))
        keep = keep[np.lexsort((order[keep], when[keep]))]
        out_seq.append(tuple(int(f) for f in keep))
        out_dist.append(when[keep])
    return out_seq, out_dist


def _match_chunk(
    xy: np.ndarray, classes: tuple[str, ...], seqs: list[tuple[int, ...]], params: UniquenessParams
) -> list[int]:
    return first_unique(xy, classes, seqs, params)


def unique_distances(
    plan: StoreyPlan,
    seqs: list[tuple[int, ...]],
    dists: list[np.ndarray],
    params: SurveyParams,
    executor: Executor | None = None,
    on_done: Callable[[int], None] | None = None,
    chunks: int | None = None,
) -> np.ndarray:
    """(S,) metres driven to a unique match per start; ``inf``: never unique within the limit."""
    order = sorted(range(len(seqs)), key=lambda i: seqs[i])
    executor = executor or LocalExecutor(1)
    n_chunks = chunks or max(1, min(len(order), 8 * executor.slots))
    size = math.ceil(len(order) / n_chunks) if order else 1
    parts = [order[lo : lo + size] for lo in range(0, len(order), size)]
    out = np.full(len(seqs), np.inf)
    calls = [
        (_match_chunk, plan.features.xy, plan.features.cls, [seqs[i] for i in p], params.matching)
        for p in parts
    ]
    for k, counts in map_unordered(executor, calls):
        for i, n in zip(parts[k], counts, strict=True):
            if n > 0:
                out[i] = float(dists[i][n - 1])
        if on_done is not None:
            on_done(len(parts[k]))
    return out


@dataclass
class StoreySurvey:
    """The survey of one storey: the plan, the per-start distances, the per-position map values."""

    plan: StoreyPlan
    distance: np.ndarray  # (S,) m, inf: never unique
    params: SurveyParams

    @property
    def position_distance(self) -> np.ndarray:
        """(M,) mean over headings of the distance capped at the limit."""
        capped = np.minimum(self.distance, self.params.limit_m)
        return np.bincount(self.plan.position, capped, len(self.plan.positions)) / self.params.headings

    @property
    def position_never(self) -> np.ndarray:
        """(M,) share of the headings that never become unique."""
        never = ~np.isfinite(self.distance)
        return np.bincount(self.plan.position, never, len(self.plan.positions)) / self.params.headings


def survey_storey(
    plan: StoreyPlan,
    params: SurveyParams,
    executor: Executor | None = None,
    on_done: Callable[[int], None] | None = None,
) -> tuple[StoreySurvey, SampleViews]:
    views = sample_views(plan, params)
    seqs, dists = sequences(plan, views, params)
    distance = unique_distances(plan, seqs, dists, params, executor, on_done)
    return StoreySurvey(plan, distance, params), views


def summarise(result: StoreySurvey) -> dict[str, object]:
    """The per-storey numbers of ``survey.json``."""
    d = result.distance
    n = len(d)
    cell = result.params.spacing**2
    finite = d[np.isfinite(d)]
    median = float(np.median(d)) if n else math.inf
    twin = result.plan.twin
    return {
        "storey": result.plan.name,
        "samples": n,
        "positions": len(result.plan.positions),
        "headings": result.params.headings,
        "area_m2": round(len(result.plan.positions) * cell, 2),
        "unique_within": {
            f"{int(r)}m": round(float(np.mean(d <= r)) if n else 0.0, 4) for r in UNIQUE_WITHIN
        },
        "median_distance_m": round(median, 2) if math.isfinite(median) else None,
        "mean_distance_m": round(float(finite.mean()), 2) if len(finite) else None,
        "never_unique_share": round(float(np.mean(~np.isfinite(d))) if n else 0.0, 4),
        "never_unique_area_m2": round(float(result.position_never.sum() * cell), 2),
        # rooms closed off by their doors: a robot there is shut in (cannot initialise from here)
        "shut_in_area_m2": round(sum(r.area_m2 for r in result.plan.shut_in), 1),
        "shut_in_rooms": [{"x": r.x, "y": r.y, "area_m2": r.area_m2} for r in result.plan.shut_in],
        # spaces a lidar alone cannot place, doors shut: with the camera off a start there fails
        "lidar_twins": [dataclasses.asdict(t) for t in result.plan.lidar_twins],
        "lidar_twin_area_m2": round(sum(t.area_m2 for t in result.plan.lidar_twins), 1),
        "lidar_twin_start_share": round(result.plan.lidar_twin_start_share, 4),
        "lidar_twin_tolerance_m": round(result.params.scan_tolerance, 3),
        # the storey is itself turned: every start has a twin (a session fails at once there)
        "self_similar": None
        if twin is None
        else {
            "turn_deg": round(twin.degrees, 1),
            "x": round(twin.centre[0], 3),
            "y": round(twin.centre[1], 3),
            "tolerance_m": round(twin.tolerance, 3),
        },
    }


def _with_landmark(
    plan: StoreyPlan,
    views: SampleViews,
    params: SurveyParams,
    current: np.ndarray,
    which: np.ndarray,
    executor: Executor | None,
) -> np.ndarray:
    """The distances of the starts ``which`` once the plan's last feature (a landmark) is there; the
    starts that confirm it only after their unique match keep their distance."""
    seqs, dists = sequences(plan, views, params, which)
    new = len(plan.features) - 1
    limit = params.limit_m
    changed = [
        j
        for j, (i, s) in enumerate(zip(which, seqs, strict=True))
        if new in s and dists[j][s.index(new)] < min(current[i], limit)
    ]
    distance = current[which].copy()
    if changed:
        distance[changed] = unique_distances(
            plan, [seqs[j] for j in changed], [dists[j] for j in changed], params, executor
        )
    return distance


@dataclass(frozen=True)
class Landmark:
    x: float
    y: float
    norm_x: float
    norm_y: float
    cls: str
    mean_distance_m: float  # the survey's mean capped distance with this and the earlier landmarks


def landmark_candidates(plan: StoreyPlan, params: SurveyParams) -> np.ndarray:
    """(C, 4) x, y, nx, ny on corridor walls, ``landmark_spacing`` apart, off the existing features."""
    out = []
    for x1, y1, x2, y2, nx, ny in plan.walls:
        length = math.hypot(x2 - x1, y2 - y1)
        if length < 1.0:
            continue
        n = max(1, int(length // params.landmark_spacing))
        for s in (np.arange(n) + 0.5) / n:
            px, py = x1 + s * (x2 - x1), y1 + s * (y2 - y1)
            if not plan.circulation.contains(px + 0.6 * nx, py + 0.6 * ny, 0.3):
                continue
            if len(plan.features) and np.hypot(*(plan.features.xy - [px, py]).T).min() < 1.0:
                continue
            out.append((px, py, nx, ny))
    cand = np.array(out, dtype=float).reshape(-1, 4)
    if len(cand) > params.landmark_candidates:
        cand = cand[np.linspace(0, len(cand) - 1, params.landmark_candidates).round().astype(int)]
    return cand


def suggest_landmarks(
    result: StoreySurvey,
    views: SampleViews,
    count: int,
    executor: Executor | None = None,
    on_done: Callable[[int], None] | None = None,
) -> tuple[list[Landmark], StoreySurvey]:
    """Greedy: the candidate wall position whose landmark (a category of its own) cuts the mean capped
    distance most, then the next one given the first. Returns the landmarks and the survey with them."""
    params = result.params
    plan, current = result.plan, result.distance
    chosen: list[Landmark] = []
    limit = params.limit_m
    pick = np.arange(0, len(plan.starts), max(1, params.landmark_stride))
    for k in range(1, count + 1):
        cls = f"{LANDMARK_CLASS}_{k}"
        best: tuple[float, np.ndarray] | None = None
        for x, y, nx, ny in landmark_candidates(plan, params):
            extra = FeatureArrays(
                np.array([[x, y]]), np.array([[nx, ny]]), np.array([LANDMARK_HEIGHT]), (cls,)
            )
            cand_plan, cand_views = with_feature(plan, views, params, extra)
            distance = _with_landmark(cand_plan, cand_views, params, current, pick, executor)
            score = float(np.minimum(distance, limit).mean())
            if best is None or score < best[0] - 1e-9:
                best = (score, np.array([x, y, nx, ny]))
            if on_done is not None:
                on_done(1)
        if best is None:
            break
        x, y, nx, ny = best[1]
        extra = FeatureArrays(np.array([[x, y]]), np.array([[nx, ny]]), np.array([LANDMARK_HEIGHT]), (cls,))
        plan, views = with_feature(plan, views, params, extra)
        current = _with_landmark(plan, views, params, current, np.arange(len(plan.starts)), executor)
        chosen.append(
            Landmark(float(x), float(y), float(nx), float(ny), cls, float(np.minimum(current, limit).mean()))
        )
    return chosen, StoreySurvey(plan, current, params)
