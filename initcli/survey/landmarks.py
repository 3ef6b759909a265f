"""The greedy landmark placement: signs on corridor walls, each of its own category, that cut the
survey's mean distance to a unique match most."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from initcli.core.features.visibility import FeatureArrays
from initcli.executor import Executor
from initcli.survey.plan import StoreyPlan, SurveyParams
from initcli.survey.run import StoreySurvey, unique_distances
from initcli.survey.sequences import SampleViews, sequences, with_feature

__all__ = ["LANDMARK_CLASS", "LANDMARK_HEIGHT", "Landmark", "landmark_candidates", "suggest_landmarks"]

LANDMARK_CLASS = "landmark"  # each suggested landmark gets its own category: landmark_1, landmark_2
LANDMARK_HEIGHT = 2.0  # m: a sign whose centre is at the camera's height


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
        distance[changed] = np.minimum(
            unique_distances(plan, [seqs[j] for j in changed], [dists[j] for j in changed], params, executor),
            distance[changed],  # the lidar's distance, or the camera's without the landmark
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
    return chosen, StoreySurvey(plan, current, params, result.lidar_distance)
