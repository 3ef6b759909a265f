"""Incremental Algorithm 1 on a survey sample's feature sequence until one hypothesis is left.

The counting is the one of :func:`initcli.match.pipeline.match_log`: the complete matches of
Algorithm 1 (Eq. 4-9, with the outlier tolerance and revisits of :class:`MatchParams`), rule 1
(sub-matches dropped), the rigid odom->BIM transform of each, and rule 3 (matches that put the robot
within ``pose_radius`` and ``beta`` of each other are one hypothesis). The sequence is noise-free,
so the detected positions are the BIM positions themselves (Algorithm 1 only uses their distances
and angles); the robot's current pose is taken at the latest feature, which keeps a count a function
of the sequence alone so that sequences sharing a prefix share its matching.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from initcli.core.hypotheses.matching import (
    OUTLIER,
    BimIndex,
    Matcher,
    MatchOverflow,
    MatchParams,
    MatchState,
)
from initcli.core.hypotheses.pose import rigid_align_batch
from initcli.core.hypotheses.ranking import drop_dominated, pose_groups, rank_order
from initcli.core.verify.params import VerificationParams
from initcli.match.pipeline import MatchOptions

__all__ = ["AMBIGUOUS", "UniquenessParams", "count_hypotheses", "first_unique"]

AMBIGUOUS = 1 << 30  # the count given to a pattern that overflowed the matcher
_MATCH = MatchOptions()  # the matching settings' one default each
_CHECKS = VerificationParams()


@dataclass(frozen=True)
class UniquenessParams:
    """The matching of ``bim-init match`` (its settings, defaults from :class:`MatchOptions`)."""

    alpha: float = _MATCH.alpha  # m, Eq. 7
    beta_deg: float = _MATCH.beta  # degrees, Eq. 9 (and the yaw tolerance of rule 3)
    max_outliers: int = _MATCH.max_outliers
    min_inliers: int = _MATCH.min_inliers
    revisits: bool = _MATCH.revisits
    pose_radius: float = _MATCH.pose_radius  # m, rule 3
    max_partials: int = 2_000_000  # the survey's own cap on partial matches (memory, time)
    # matched features a unique match needs before the session claims it (its verification's
    # min_claim_inliers): the survey predicts the session, so it waits as long
    min_claim: int = _CHECKS.min_claim_inliers

    def match_params(self) -> MatchParams:
        return MatchParams(
            alpha=self.alpha,
            beta=math.radians(self.beta_deg),
            max_outliers=self.max_outliers,
            min_inliers=self.min_inliers,
            revisits=self.revisits,
            max_partials=self.max_partials,
        )


def count_hypotheses(state: MatchState, index: BimIndex, params: UniquenessParams) -> int:
    """Pose-distinct hypotheses of a match state (rules 1 and 3)."""
    mp = params.match_params()
    if state.n < params.min_inliers:
        return 0
    rows = state.matches(mp)
    assign, n_out, cost = state.assign[rows], state.n_out[rows], state.cost[rows]
    keep = drop_dominated(assign, n_out)
    assign, n_out, cost = assign[keep], n_out[keep], cost[keep]
    if len(assign) <= 1:
        return len(assign)
    inlier = assign != OUTLIER
    bim = index.xy[np.where(inlier, assign, 0)]
    src = np.broadcast_to(state.s_xy, bim.shape)
    yaw, t = rigid_align_batch(src, bim, inlier.astype(float))
    here = state.s_xy[-1]
    c, s = np.cos(yaw), np.sin(yaw)
    current = np.column_stack([t[:, 0] + c * here[0] - s * here[1], t[:, 1] + s * here[0] + c * here[1], yaw])
    _, reps = pose_groups(
        current,
        np.zeros(len(current), dtype=np.intp),
        rank_order(n_out, cost),
        params.pose_radius,
        math.radians(params.beta_deg),
    )
    return len(reps)


def first_unique(
    xy: np.ndarray, classes: Sequence[str], sequences: Sequence[Sequence[int]], params: UniquenessParams
) -> list[int]:
    """For each sequence of feature indices (in the order confirmed), the number of features after
    which exactly one hypothesis is left (and at least ``min_claim`` were seen), or -1 when that never
    happens.

    Sequences are matched in lexicographic order so that a shared prefix is matched once.
    """
    index = BimIndex(np.asarray(xy, dtype=float).reshape(-1, 2), list(classes))
    matcher = Matcher(index, params.match_params())
    order = sorted(range(len(sequences)), key=lambda i: tuple(sequences[i]))
    out = [-1] * len(sequences)
    stack: list[tuple[int, MatchState | None, int]] = []  # (feature, state after it, count)
    for i in order:
        seq = tuple(int(f) for f in sequences[i])
        shared = 0
        while shared < min(len(stack), len(seq)) and stack[shared][0] == seq[shared]:
            shared += 1
        del stack[shared:]
        for n in range(len(seq)):
            if n < len(stack):
                count = stack[n][2]
            else:
                before = stack[-1][1] if stack else MatchState.empty()
                if before is None:  # overflowed: stays ambiguous
                    state, count = None, AMBIGUOUS
                else:
                    f = seq[n]
                    try:
                        state = matcher.extend(before, index.xy[f], index.classes[f])
                        count = count_hypotheses(state, index, params)
                    except MatchOverflow:
                        state, count = None, AMBIGUOUS
                stack.append((seq[n], state, count))
            if count == 1 and n + 1 >= params.min_claim:
                out[i] = n + 1
                break
    return out
