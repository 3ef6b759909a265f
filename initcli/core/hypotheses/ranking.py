"""From the matches of Algorithm 1 to counted, ranked hypotheses and a verdict.

A *match* assigns every confirmed feature a BIM feature or ``OUTLIER`` (see
:mod:`initcli.core.hypotheses.matching`). A *hypothesis* is a robot pose with the matches that support it.
The rules, in the order they are applied (tested in ``tests/test_match_hypotheses.py`` and
``tests/test_match_pipeline.py``):

0. **Which matches exist.** A full match needs ``min_inliers`` (3) features (§3.3.4). A match that
   declares up to ``max_outliers`` detections false needs only 2 inliers, the fewest that place the
   robot: with 3 detections of which one may be false, "it was false" stays an alternative, so 3
   detections can never give a unique match under ``--max-outliers 1`` unless every such
   alternative puts the robot at the same pose.
1. **Sub-matches are dropped.** A match with outlier set O is dropped when a match with fewer
   outliers, O' a strict subset of O, assigns the same BIM features to every feature outside O:
   declaring a detection false is only an alternative when its being true was not also
   consistent at that place. (Matches that differ *only* in which detection is the outlier and
   sit at the same place are merged by rule 3.)
2. **Ranking.** Fewer outliers first, then lower cost J (Eq. 14 over the inliers).
3. **Only pose-distinct hypotheses count.** In rank order, a match whose current robot pose lies
   within ``radius`` (m) and ``yaw_tolerance`` (rad) of a better-ranked hypothesis on the same
   storey joins it; otherwise it founds a new hypothesis. The best-ranked match of each group
   represents it. Poses for this test are the rigid (Kabsch) alignment of the inliers.
4. **Verdict.** 0 hypotheses -> ``no consistent match``; 1 -> ``unique match``; otherwise
   ``N hypotheses``. Hypotheses with outliers count exactly like full matches: a full match
   elsewhere does *not* rule out an outlier-tolerant one (that would turn a false positive that
   happens to fit a wrong place into a wrong unique match), it only ranks above it. The price is
   measured in ``benchmarks/bench_match.py``: more logs end ambiguous (the robot must see more),
   none ends in a wrong unique match.
5. **Confidence** of a hypothesis: w = exp(-J / tau) * eps^(outliers), normalised over all
   hypotheses (not only the top K); tau = 0.5 and eps = 0.1 by default. A heuristic for
   ranking display, not a probability.

Beyond the paper, the session asks :func:`one_place`: rule 3 tells hypotheses apart by the rigid
fit over *all* their matched features, so after a long drive with odometry drift (a 2 % wheel-scale
error is 2 m in 100 m) two explanations of the oldest features differ there while both put the
robot on the same spot now (ntu_hallway, construction, seed 82: two hypotheses 0.1 m from the truth
for the last 15 m of a failed session); such a set is one place, and its best is checked as a
unique match.
"""

from __future__ import annotations

import enum
import math
from collections import defaultdict

import numpy as np

from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.matching import OUTLIER

__all__ = [
    "VERDICT_NONE",
    "VERDICT_UNIQUE",
    "Verdict",
    "confidences",
    "distinct_places",
    "drop_dominated",
    "one_place",
    "pose_groups",
    "rank_order",
    "verdict_text",
]

VERDICT_UNIQUE = "unique match"
VERDICT_NONE = "no consistent match"


class Verdict(enum.StrEnum):
    """Rule 4's outcome: one place, several, or none. UNIQUE and NONE are their verdict lines; the
    line of AMBIGUOUS names the count (:func:`verdict_text`). The command's exit code for each is
    ``initcli.cli.exit_codes``'s, not the library's."""

    UNIQUE = VERDICT_UNIQUE
    AMBIGUOUS = "ambiguous"
    NONE = VERDICT_NONE

    @classmethod
    def of(cls, count: int) -> Verdict:
        """The outcome of ``count`` pose-distinct hypotheses (the one :func:`verdict_text` words)."""
        if count <= 0:
            return cls.NONE
        return cls.UNIQUE if count == 1 else cls.AMBIGUOUS


def verdict_text(count: int) -> str:
    """The verdict line for ``count`` pose-distinct hypotheses."""
    if count <= 0:
        return VERDICT_NONE
    if count == 1:
        return VERDICT_UNIQUE
    return f"{count} hypotheses"


def drop_dominated(assign: np.ndarray, n_out: np.ndarray) -> np.ndarray:
    """Rule 1: boolean mask of the matches to keep (see the module docstring)."""
    assign = np.asarray(assign)
    n_out = np.asarray(n_out)
    keep = np.ones(len(assign), dtype=bool)
    if len(assign) == 0 or n_out.max(initial=0) == 0:
        return keep
    is_out = assign == OUTLIER
    patterns: dict[bytes, list[int]] = defaultdict(list)
    for h in np.flatnonzero(n_out > 0):
        patterns[is_out[h].tobytes()].append(int(h))
    for key, members in patterns.items():
        mask = np.frombuffer(key, dtype=bool)
        k = int(mask.sum())
        # candidates: fewer outliers, all of them inside this outlier set
        cand = np.flatnonzero((n_out < k) & ~(is_out[:, ~mask].any(axis=1)))
        if len(cand) == 0:
            continue
        masked = assign[cand].copy()
        masked[:, mask] = OUTLIER
        seen = {row.tobytes() for row in np.ascontiguousarray(masked)}
        rows = np.ascontiguousarray(assign[members])
        for member, row in zip(members, rows, strict=True):
            if row.tobytes() in seen:
                keep[member] = False
    return keep


def rank_order(n_out: np.ndarray, cost: np.ndarray) -> np.ndarray:
    """Rule 2: indices sorted by (outliers, cost)."""
    return np.lexsort((np.asarray(cost), np.asarray(n_out)))


def pose_groups(
    poses: np.ndarray, storey: np.ndarray, order: np.ndarray, radius: float, yaw_tolerance: float
) -> tuple[np.ndarray, list[int]]:
    """Rule 3: group matches by current pose. Returns a group label per match and the representatives
    (indices into ``poses``) in rank order; label g belongs to representative ``reps[g]``."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    labels = np.full(len(poses), -1, dtype=np.intp)
    reps: list[int] = []
    cell = max(radius, 1e-9)
    grid: dict[tuple[int, int, int], list[int]] = defaultdict(list)
    for h in np.asarray(order, dtype=np.intp):
        x, y, yaw = poses[h]
        g = int(storey[h])
        cx, cy = math.floor(x / cell), math.floor(y / cell)
        found = -1
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for label in grid.get((g, cx + dx, cy + dy), ()):
                    r = poses[reps[label]]
                    if (
                        math.hypot(r[0] - x, r[1] - y) <= radius
                        and abs((r[2] - yaw + math.pi) % (2 * math.pi) - math.pi) <= yaw_tolerance
                    ):
                        found = label if found < 0 else min(found, label)
        if found < 0:
            found = len(reps)
            reps.append(int(h))
            grid[(g, cx, cy)].append(found)
        labels[h] = found
    return labels, reps


def one_place(storeys: list[str], poses: list[Pose2D], radius: float, yaw_tolerance: float) -> bool:
    """Do two or more hypotheses (their storeys and the poses they report, best first) all lie
    within ``radius`` (m) and ``yaw_tolerance`` (rad) of the best, on its storey?"""
    if len(poses) < 2:
        return False
    best = poses[0]
    return all(
        storey == storeys[0] and pose.distance_to(best) <= radius and pose.yaw_error(best) <= yaw_tolerance
        for storey, pose in zip(storeys[1:], poses[1:], strict=True)
    )


def distinct_places(
    storeys: list[str], poses: list[Pose2D], radius: float, yaw_tolerance: float
) -> list[int]:
    """Indices of the hypotheses (their storeys and the poses they report, best first) that are not
    within ``radius`` (m) and ``yaw_tolerance`` (rad) of a better one on the same storey: one per
    place (rule 3 groups matches by the rigid fit over all their features, which odometry drift can
    split while the pose they report is one)."""
    kept: list[int] = []
    for i, (storey, pose) in enumerate(zip(storeys, poses, strict=True)):
        if not any(
            storeys[k] == storey
            and pose.distance_to(poses[k]) <= radius
            and pose.yaw_error(poses[k]) <= yaw_tolerance
            for k in kept
        ):
            kept.append(i)
    return kept


def confidences(cost: np.ndarray, n_out: np.ndarray, tau: float = 0.5, eps: float = 0.1) -> np.ndarray:
    """Rule 5: normalised exp(-J/tau) * eps^outliers over the given hypotheses."""
    cost = np.asarray(cost, dtype=float)
    if len(cost) == 0:
        return cost
    logw = -cost / tau + np.asarray(n_out, dtype=float) * math.log(eps)
    w = np.exp(logw - logw.max())
    normalised: np.ndarray = w / w.sum()
    return normalised
