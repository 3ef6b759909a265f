"""The survey's run: the matching of every start's sequence, in chunks on an executor, to the
distance at which it becomes unique, and the survey of one storey that holds those distances."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from initcli.executor import Executor, LocalExecutor, map_unordered
from initcli.survey.lidar import LoopRegistration, lidar_distances
from initcli.survey.plan import StoreyPlan, SurveyParams
from initcli.survey.sequences import SampleViews, sample_views, sequences
from initcli.survey.uniqueness import UniquenessParams, first_unique

__all__ = ["StoreySurvey", "lidar_along", "survey_storey", "unique_distances"]


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
    distance: np.ndarray  # (S,) m, inf: never unique (the camera or the lidar, whichever is first)
    params: SurveyParams
    lidar_distance: np.ndarray | None = None  # (S,) m until the lidar places the start; None: not run

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
    if params.camera_on:
        seqs, dists = sequences(plan, views, params)
        distance = unique_distances(plan, seqs, dists, params, executor, on_done)
    else:  # no camera: the lidar alone
        distance = np.full(len(plan.starts), np.inf)
        if on_done is not None:
            on_done(len(plan.starts))
    lidar = lidar_along(plan, views, params, executor)
    if lidar is not None:
        distance = np.minimum(distance, lidar)
    return StoreySurvey(plan, distance, params, lidar), views


def lidar_along(
    plan: StoreyPlan, views: SampleViews, params: SurveyParams, executor: Executor | None = None
) -> np.ndarray | None:
    """(S,) m until the session's lidar registration places each start (:mod:`initcli.survey.lidar`;
    none on a self-similar storey or in a lidar twin's space, where sessions fail while the doors
    stay shut); None where the registration is off or the storey has no map. The loops'
    registrations are shared out on ``executor`` in chunks."""
    reg = params.registration
    if not reg.enabled or plan.registration_map is None or plan.scan_segments is None:
        return None
    if plan.twin is not None:  # a self-similar storey: the session ends at once, whatever it scans
        return np.full(len(plan.starts), np.inf)
    key = (repr(reg), repr(params.lidar), params.scan_tolerance)  # the settings it was made with
    if key not in plan.lidar_placed:
        plan.lidar_placed[key] = _placed(plan, params, executor or LocalExecutor(1))
    distance = lidar_distances(views.entries, plan.lidar_placed[key], plan.loops, reg, params.limit_m)
    if len(plan.starts):  # a lidar twin's space, doors shut (noise-free scans may tell it apart)
        distance[plan.in_lidar_twin(plan.starts[:, :2])] = np.inf
    return distance


def _placed(plan: StoreyPlan, params: SurveyParams, executor: Executor) -> list[np.ndarray]:
    """:meth:`LoopRegistration.placed_along` for each of the plan's loops, its registrations shared
    out on ``executor`` in chunks; none placed on a loop wholly inside a lidar twin's space (not
    registered at all)."""
    assert plan.scan_segments is not None and plan.registration_map is not None
    along = LoopRegistration(
        plan.scan_segments,
        [plan.registration_map],
        plan.name,
        params.registration,
        params.scan_tolerance,
        params.lidar,
    )
    points = [[] if plan.in_lidar_twin(loop.xy).all() else along.points(loop) for loop in plan.loops]
    size = max(1, math.ceil(sum(map(len, points)) / (4 * executor.slots)))
    chunks = [(k, lo) for k, p in enumerate(points) for lo in range(0, len(p), size)]
    calls = [(along.placed_at, plan.loops[k], points[k][lo : lo + size]) for k, lo in chunks]
    right: list[list[bool]] = [[False] * len(p) for p in points]
    for j, got in map_unordered(executor, calls):
        k, lo = chunks[j]
        right[k][lo : lo + len(got)] = got
    return [along.placed_from(loop, points[k], right[k]) for k, loop in enumerate(plan.loops)]
