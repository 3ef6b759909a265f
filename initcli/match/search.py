"""Steps 3-7 of the pipeline on the confirmed features (paper §3.3.2-3.3.3, §3.3.5): Algorithm 1 on
every storey searched with the outlier budget grown as needed, rule 1 (sub-matches), ranking and
pose-distinct counting (:mod:`initcli.core.hypotheses.ranking`), the pose of each shown hypothesis
(Eq. 10-13 or rigid, rectified by Eq. 17), and the verdict, into a :class:`MatchReport`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from bimtools.site.load import Site, StoreyModel
from initcli.config.matching import MatchOptions
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.hypotheses.matching import OUTLIER, BimIndex, Matcher, MatchOverflow, MatchParams
from initcli.core.hypotheses.pose import estimate_pose, rigid_align_batch
from initcli.core.hypotheses.ranking import confidences, drop_dominated, pose_groups, rank_order
from initcli.core.hypotheses.rectify import WallArray, rectify_pose
from initcli.io.detection_log import DetectionLog
from initcli.match.landmarks import travel_at
from initcli.match.report import DECIDED_BY_PAPER, Hypothesis, MatchReport

__all__ = ["ESCALATED_PARTIALS", "search", "transform_poses_batch"]

ESCALATED_PARTIALS = 2_000_000  # partial-match cap once the outlier budget grows (memory, time)


@dataclass
class _Candidates:
    storey: list[str] = field(default_factory=list)
    assign: list[np.ndarray] = field(default_factory=list)
    n_out: list[np.ndarray] = field(default_factory=list)
    cost: list[np.ndarray] = field(default_factory=list)
    transform: list[np.ndarray] = field(default_factory=list)  # (H, 3) odom->BIM x, y, yaw
    indexes: dict[str, BimIndex] = field(default_factory=dict)  # per storey


def search(
    report: MatchReport,
    site: Site,
    cmap: ClassMap,
    features: list[ConfirmedFeature],
    log: DetectionLog,
    opts: MatchOptions,
    escalate: bool,
    max_partials: int | None = None,
) -> bool:
    """Steps 3-7 on ``features`` over the storeys ``report.storeys`` into ``report`` (the camera's
    outlier budget grown when ``escalate``; ``max_partials``: a lower partial-match cap than
    MatchParams'). Whether a match was found: not when matching stopped at the partial-match cap
    either (``report.overflow`` then, its verdict ambiguous)."""
    s_xy = np.array([[f.x, f.y] for f in features]).reshape(-1, 2)
    s_cls = [f.cls for f in features]
    s_travel = travel_at(log.odom, [f.t_confirmed for f in features])
    is_landmark = opts.match_params().is_landmark
    n_camera = sum(not is_landmark(c) for c in s_cls)
    params = opts.match_params(camera=n_camera >= 2)
    if max_partials is not None:
        params = replace(params, max_partials=max_partials)
    budget = opts.outlier_budget(n_camera) if escalate else 0
    while True:
        try:
            cand = _candidates(site, cmap, report.storeys, s_xy, s_cls, params, s_travel)
        except MatchOverflow as exc:
            report.warnings.append(f"matching stopped: {exc}; the detected pattern is far too ambiguous")
            report.decide(max(2, params.max_partials))
            report.n_hypotheses = params.max_partials
            report.overflow = True
            return False
        if cand.storey or params.max_outliers >= budget:
            break
        params = replace(params, max_outliers=params.max_outliers + 1, max_partials=ESCALATED_PARTIALS)
    if params.max_outliers > opts.max_outliers and cand.storey:
        report.notes.append(
            f"no match tolerates {opts.max_outliers} outlier(s); matched with {params.max_outliers} "
            f"(outlier_share {opts.outlier_share:g} of {len(features)} features)"
        )
    report.outliers_allowed = params.max_outliers
    if cand.storey:
        _rank(report, site, cand, s_xy)
    return bool(cand.storey)


def _storey_candidates(
    model: StoreyModel,
    cmap: ClassMap,
    s_xy: np.ndarray,
    s_cls: Sequence[str],
    params: MatchParams,
    s_travel: np.ndarray | None = None,
) -> tuple[BimIndex, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    index = BimIndex(
        np.array([[f.x, f.y] for f in model.features]), [cmap.canonical(f.category) for f in model.features]
    )
    matcher = Matcher(index, params)
    state = matcher.match(s_xy, s_cls, s_travel)
    rows = state.matches(params)
    assign, n_out, cost = state.assign[rows], state.n_out[rows], state.cost[rows]
    # rule 1 over the camera's outliers and the camera's columns: with the landmarks' columns in the
    # outlier set, a hypothesis with a false door and a skipped corner dominated itself and vanished
    # (a landmark sub-match has the pose of its match: rule 3 merges them)
    camera = np.array([not params.is_landmark(c) for c in s_cls], dtype=bool)
    keep = drop_dominated(assign[:, camera], n_out)
    assign, n_out, cost = assign[keep], n_out[keep], cost[keep]
    if len(assign):
        inlier = assign != OUTLIER
        bim = index.xy[np.where(inlier, assign, 0)]
        src = np.broadcast_to(s_xy, bim.shape)
        yaw, t = rigid_align_batch(src, bim, inlier.astype(float))
        transform = np.column_stack([t, yaw])
    else:
        transform = np.zeros((0, 3))
    return index, assign, n_out, cost, transform


def transform_poses_batch(transforms: np.ndarray, pose: Pose2D) -> np.ndarray:
    """``T_h * pose`` for every transform row (x, y, yaw) of ``transforms`` -> (H, 3)."""
    c, s = np.cos(transforms[:, 2]), np.sin(transforms[:, 2])
    x = transforms[:, 0] + c * pose.x - s * pose.y
    y = transforms[:, 1] + s * pose.x + c * pose.y
    return np.column_stack([x, y, wrap_angle(transforms[:, 2] + pose.yaw)])


def _candidates(
    site: Site,
    cmap: ClassMap,
    storey_names: list[str],
    s_xy: np.ndarray,
    s_cls: Sequence[str],
    params: MatchParams,
    s_travel: np.ndarray | None = None,
) -> _Candidates:
    """Algorithm 1 and rule 1 on every storey searched (MatchOverflow past the partial-match cap)."""
    cand = _Candidates()
    for name in storey_names:
        model = site.storeys[name]
        index, assign, n_out, cost, transform = _storey_candidates(model, cmap, s_xy, s_cls, params, s_travel)
        cand.indexes[name] = index
        cand.storey.extend([name] * len(assign))
        cand.assign.append(assign)
        cand.n_out.append(n_out)
        cand.cost.append(cost)
        cand.transform.append(transform)
    return cand


def _rank(report: MatchReport, site: Site, cand: _Candidates, s_xy: np.ndarray) -> None:
    """Steps 4-7 on the candidates of every storey: rank (rule 2), group by pose (rule 3), the
    confidences (rule 5), the pose of each shown hypothesis, and the verdict, into ``report``."""
    opts, odom_pose = report.options, report.odom_pose
    assign = np.concatenate(cand.assign)
    n_out = np.concatenate(cand.n_out)
    cost = np.concatenate(cand.cost)
    transform = np.concatenate(cand.transform)
    storey_ids = np.array([report.storeys.index(s) for s in cand.storey])
    current = transform_poses_batch(transform, odom_pose)  # robot pose in BIM per match (rigid)
    # rule 2: camera outliers first, then the lidar landmarks' (clutter is common: they weigh less)
    order = rank_order(n_out * (assign.shape[1] + 1) + (assign == OUTLIER).sum(axis=1), cost)
    labels, reps = pose_groups(
        current, storey_ids, order, opts.pose_radius, math.radians(opts.beta)
    )  # rule 3
    support = np.bincount(labels, minlength=len(reps))
    conf = confidences(cost[reps], n_out[reps])  # rule 5

    hyps: list[Hypothesis] = []
    for rank, h in enumerate(reps[: opts.top], start=1):
        storey = cand.storey[h]
        model = site.storeys[storey]
        row = assign[h]
        pose, rect_pose, moved = _hypothesis_pose(model, cand.indexes[storey], row, s_xy, odom_pose, opts)
        hyps.append(
            Hypothesis(
                rank=rank,
                storey=storey,
                assignment=tuple(int(a) for a in row),
                matches=[model.features[int(a)].id if a != OUTLIER else None for a in row],
                n_outliers=int(n_out[h]),
                cost=float(cost[h]),
                pose=pose,
                rectified_pose=rect_pose,
                transform=pose * odom_pose.inverse(),
                confidence=float(conf[rank - 1]),
                support=int(support[labels[h]]),
                rectified=moved,
            )
        )
    report.hypotheses = hyps
    report.n_hypotheses = len(reps)
    report.decide(len(reps))
    report.decided_by = DECIDED_BY_PAPER if len(reps) == 1 else None
    rep_storeys = {cand.storey[h] for h in reps}
    report.storey = next(iter(rep_storeys)) if len(rep_storeys) == 1 else None


def _hypothesis_pose(
    model: StoreyModel,
    index: BimIndex,
    row: np.ndarray,
    s_xy: np.ndarray,
    odom_pose: Pose2D,
    opts: MatchOptions,
) -> tuple[Pose2D, Pose2D | None, bool]:
    """Steps 5-6 for one match: the robot's pose now (Eq. 10-13 or rigid), rectified with the
    storey's walls (Eq. 17) when it has walls, and whether rectification moved it."""
    inl = np.flatnonzero(row != OUTLIER)
    bim_xy = index.xy[row[inl]]
    pose = estimate_pose(opts.pose_method, bim_xy, s_xy[inl], odom_pose, opts.pose_window or None)
    if not model.walls:
        return pose, None, False
    walls = WallArray.from_segments([(w.x1, w.y1, w.x2, w.y2, *w.normal) for w in model.walls])
    feature_robot = odom_pose.apply_inverse(s_xy[inl[-1]])
    rect_pose, rect = rectify_pose(  # Eq. 17, never turning the pose past beta
        pose, walls, opts.d_thre, bim_xy[-1], feature_robot, math.radians(opts.beta)
    )
    return pose, rect_pose, rect.moved
