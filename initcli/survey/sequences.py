"""Per start sample: what it sees before it reaches its loop, and the features it confirms (after
``min_sightings`` images, as the detection filter does) in order, with the distance driven to each."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from initcli.core.features.visibility import FeatureArrays, visible
from initcli.survey.exploration import Entry, join_loop, look_round
from initcli.survey.plan import StoreyPlan, SurveyParams, cumulative_sightings

__all__ = ["SampleViews", "sample_views", "sequences", "with_feature"]


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
        np.hstack([c, cumulative_sightings(visible(lp.poses, extra, plan.occluders, params.camera))])
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
