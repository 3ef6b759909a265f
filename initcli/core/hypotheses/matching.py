"""Algorithm 1 (Eq. 4-9): bottom-up feature matching, indexed, incremental, with outlier tolerance.

Published algorithm (kept literally; ``benchmarks/_oracle.py`` holds a plain transcription and
``tests/initcli/core/hypotheses/test_matching.py`` checks that this module returns the same set of matches on
random cases):

- every BIM feature b_u with label(b_u) = label(s_1) starts a candidate;
- s_2 is matched to every b_v != b_u of its label with z_d = 1 (Eq. 7: |d^B_uv - d^S_12| <= alpha);
- each later s_i is matched to every unused b_w of its label with z = 1 (Eq. 9) for the triple
  (s_{i-2}, s_{i-1}, s_i): z_d for (i-2, i-1) and (i-2, i) and |theta_uvw - theta_ijk| <= beta
  (Eq. 8; the angle difference is wrapped, see :func:`initcli.core.hypotheses.pattern.angle_difference`);
- partial matches that find no b_w for s_i are dropped.

Indexing (instead of scanning all of B): per class, a bucket grid of the BIM positions
(:class:`initcli.core.geometry.nearest.PointGrid`, exact radius queries). For a triple,
(b_u, b_v) and the odom triangle fix where b_w must lie -- within alpha of the distance d^S_{i-2,i}
from b_u and within beta of the angle theta_ijk from the direction b_u->b_v, an annular sector --
so one batched ball query per step around the predicted point returns a superset of the
candidates, which are then tested with exactly the published criteria. The first pair uses a
ball query of radius d^S_12 + alpha around b_u (the annulus). Matching is incremental:
:meth:`Matcher.extend` adds one detected feature to an existing :class:`MatchState`.

Outlier tolerance (the one improvement over the paper, measured in ``benchmarks/bench_match.py``):
a detected feature may be declared an *outlier* (a false or misclassified detection), matched
to nothing (``-1``, ``null`` in the JSON). Definition: a match with outlier set O is exactly an
Algorithm-1 match of the subsequence S without O -- the pair/triple criteria chain over the
inliers, skipping outliers -- with |O| <= ``max_outliers``. A full match needs ``min_inliers`` (3)
features; a match with outliers needs ``min_inliers_outlier`` (2) inliers, the fewest that place
the robot, so that with few detections the alternative "one of them was false" is enumerated
(and keeps the verdict ambiguous) instead of being dropped.
The cost (Eq. 14) is taken over the inliers. How such matches are ranked against full matches
and counted is defined in :mod:`initcli.core.hypotheses.ranking` (fewer outliers first; sub-matches of
a match with fewer outliers are dropped; only pose-distinct hypotheses count).

Lidar landmarks (beyond the paper, :class:`LandmarkMatching`; None: every feature is the camera's):
wall corners and openings of the scans join S with their own labels. Between two landmarks Eq. 7
and Eq. 9 use the landmarks' alpha plus a drift allowance per metre of odometry travel between
their confirmations (at most the camera's alpha); a landmark inlier counts ``weight`` toward
``min_inliers``; landmark outliers (geometry the BIM lacks) have their own budget, a share of the
landmarks so far (at least one), declared at any point of a partial match (a row of one or two
inliers too: a stack's corner right after the first matched corner must not end the true place).
``n_out`` counts the camera's outliers only. In a sequence with camera features
(:meth:`initcli.config.matching.MatchingSettings.landmark_matching` with ``camera=True``) every
landmark may be an outlier, and a landmark joins a candidate only once it holds two camera
features: most corners a lidar sees in a corridor are clutter, and a budget would rule out the true
place while a chance fit survives.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.nearest import PointGrid
from initcli.core.hypotheses.pattern import angle_difference, pair_distance, rotation_angle

__all__ = [
    "BimIndex",
    "LandmarkMatching",
    "MatchOverflow",
    "MatchParams",
    "MatchState",
    "Matcher",
    "OUTLIER",
    "match_sequence",
]

OUTLIER = -1


@dataclass(frozen=True)
class LandmarkMatching:
    """How Algorithm 1 treats lidar landmarks in a mixed sequence (beyond the paper; the module doc,
    "Lidar landmarks"). No defaults here: the ``landmark_*`` fields of
    ``initcli.config.matching.MatchingSettings``."""

    classes: frozenset[str]  # canonical class names of the lidar landmarks
    alpha: float  # m: Eq. 7 threshold between two landmarks confirmed at the same travel
    drift: float  # m per m of odometry travel between the two confirmations, added to alpha
    weight: float  # what one landmark counts toward min_inliers (a camera feature counts 1)
    outlier_share: float  # of the first k landmarks, floor(share * k) (at least 1) may be outliers
    # True (a sequence with camera features): a landmark joins a candidate only once it holds two
    # camera features (its pose fixed, so Eq. 9 places the landmark within centimetres) and never
    # starts one; the search stays small with every landmark allowed to be an outlier
    anchored: bool = False

    def budget(self, k: int) -> int:
        """Landmark outliers a partial match of the first ``k`` landmarks may declare (0 if share is 0)."""
        return max(1, math.floor(self.outlier_share * k + 1e-9)) if self.outlier_share > 0 else 0


class MatchOverflow(RuntimeError):
    """More partial matches than ``MatchParams.max_partials``: the pattern is far too ambiguous."""


@dataclass(frozen=True)
class MatchParams:
    """Thresholds of Algorithm 1 and of the outlier tolerance.

    The user-tunable ones have no default here: callers pass them (their one default is
    ``initcli.match.pipeline.MatchOptions``, where ``beta`` is in degrees).
    """

    alpha: float  # m: distance threshold of Eq. 7
    beta: float  # rad: angle threshold of Eq. 9
    max_outliers: int  # detections that may be treated as false/misclassified
    min_inliers: int  # matched features a full match needs (§3.3.4: three or more)
    # Second improvement over the paper (measured in benchmarks/bench_match.py): allow a detected
    # feature to match a BIM feature already matched earlier in S_object (a revisit). False is the
    # literal Algorithm 1.
    revisits: bool
    # A match that declares outliers needs only enough inliers to place the robot (2): with n
    # detections of which up to max_outliers may be false, "one of them was false" must always be
    # enumerated as an alternative, never silently dropped -- otherwise 3 detections including one
    # false one could yield a wrong unique match (measured in benchmarks/bench_match.py).
    min_inliers_outlier: int = 2
    max_partials: int = 20_000_000  # safety cap on partial matches held in memory
    landmarks: LandmarkMatching | None = None  # None: every feature is a camera feature

    def is_landmark(self, cls: str) -> bool:
        return self.landmarks is not None and cls in self.landmarks.classes


class BimIndex:
    """B_object (Eq. 4) of one storey, indexed per class for Algorithm 1.

    ``classes`` are canonical class names (see :mod:`initcli.core.features.classes`); comparisons are exact.
    """

    def __init__(self, xy: np.ndarray, classes: Sequence[str]) -> None:
        self.xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        self.classes = [str(c) for c in classes]
        if len(self.classes) != len(self.xy):
            raise ValueError("xy and classes differ in length")
        self.members: dict[str, np.ndarray] = {}
        for name in sorted(set(self.classes)):
            self.members[name] = np.array([i for i, c in enumerate(self.classes) if c == name], dtype=np.intp)
        self.grids: dict[str, PointGrid] = {
            name: PointGrid(self.xy[idx]) for name, idx in self.members.items()
        }

    def __len__(self) -> int:
        return len(self.xy)

    def class_members(self, cls: str) -> np.ndarray:
        return self.members.get(cls, np.zeros(0, dtype=np.intp))

    def ball(self, centres: np.ndarray, cls: str, radius: float) -> tuple[np.ndarray, np.ndarray]:
        """All pairs (query row, BIM index) with a ``cls`` feature within ``radius`` of the centre,
        sorted by row, then index (one batched query of the class's bucket grid)."""
        centres = np.asarray(centres, dtype=float).reshape(-1, 2)
        idx = self.members.get(cls)
        if idx is None or len(centres) == 0 or radius < 0:
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        rows, local = self.grids[cls].within(centres, radius)
        return rows, idx[local]


@dataclass
class MatchState:
    """All partial matches of the first ``n`` detected features (the set M of Algorithm 1).

    Row r is one partial match: ``assign[r, i]`` is the BIM index m(s_i) or ``OUTLIER``.
    ``last2``/``last1`` are the S indices of the second-to-last and last inliers (-1 if none),
    ``cost`` the accumulated Eq. 14 over the inliers.
    """

    s_xy: np.ndarray  # (n, 2) detected features in the odom frame
    s_cls: list[str]
    assign: np.ndarray  # (K, n) int
    n_out: np.ndarray  # (K,) camera features declared outliers
    n_in: np.ndarray  # (K,) inliers, camera features and landmarks
    last2: np.ndarray  # (K,)
    last1: np.ndarray  # (K,)
    cost: np.ndarray  # (K,)
    n_lm: np.ndarray | None = None  # (K,) landmark inliers (None: zeros)
    n_lm_out: np.ndarray | None = None  # (K,) landmarks declared outliers (None: zeros)
    s_travel: np.ndarray | None = None  # (n,) m of odometry travel at each confirmation (None: zeros)
    s_lidar: np.ndarray | None = None  # (n,) bool: a lidar landmark (None: none is)

    def __post_init__(self) -> None:
        k, n = len(self.cost), len(self.s_cls)
        if self.n_lm is None:
            self.n_lm = np.zeros(k, dtype=np.intp)
        if self.n_lm_out is None:
            self.n_lm_out = np.zeros(k, dtype=np.intp)
        if self.s_travel is None:
            self.s_travel = np.zeros(n)
        if self.s_lidar is None:
            self.s_lidar = np.zeros(n, dtype=bool)

    @property
    def n(self) -> int:
        return len(self.s_cls)

    def __len__(self) -> int:
        return len(self.cost)

    @staticmethod
    def empty() -> MatchState:
        one = np.zeros(1, dtype=np.intp)
        return MatchState(
            s_xy=np.zeros((0, 2)),
            s_cls=[],
            assign=np.zeros((1, 0), dtype=np.intp),
            n_out=one.copy(),
            n_in=one.copy(),
            last2=one - 1,
            last1=one - 1,
            cost=np.zeros(1),
        )

    def complete(
        self, min_inliers: int, min_inliers_outlier: int = 2, landmark_weight: float = 1.0
    ) -> np.ndarray:
        """Indices of rows that are matches: a full match needs ``min_inliers`` inliers, a match with
        camera outliers ``min_inliers_outlier`` (at least 2 either way); a landmark inlier counts
        ``landmark_weight`` toward them (landmark outliers are expected: clutter, hoardings)."""
        need = np.where(self.n_out == 0, max(2, min_inliers), max(2, min_inliers_outlier))
        assert self.n_lm is not None
        count = (self.n_in - self.n_lm) + landmark_weight * self.n_lm
        return np.flatnonzero((count >= need - 1e-9) & (self.n_in >= 2))

    def matches(self, params: MatchParams) -> np.ndarray:
        """Indices of the rows that are complete matches under ``params``."""
        weight = params.landmarks.weight if params.landmarks is not None else 1.0
        return self.complete(params.min_inliers, params.min_inliers_outlier, weight)


_ROW_FIELDS = ("assign", "n_out", "n_in", "last2", "last1", "cost", "n_lm", "n_lm_out")


def _rows(state: MatchState, keep: np.ndarray) -> dict[str, np.ndarray]:
    return {name: getattr(state, name)[keep] for name in _ROW_FIELDS}


def _sector_radius(d: float, alpha: float, beta: float) -> float:
    """Radius around the predicted point (d, theta) that covers the annular sector of Eq. 7/9.

    The sector is {rho in [d - alpha, d + alpha], phi in [theta - beta, theta + beta]} in polar
    coordinates about b_u; its farthest points from (d, theta) are its corners.
    """
    cb = math.cos(min(beta, math.pi))
    r2 = 0.0
    for rho in (max(0.0, d - alpha), d + alpha):
        r2 = max(r2, d * d + rho * rho - 2.0 * d * rho * cb)
    return math.sqrt(max(r2, 0.0)) + 1e-6 * (1.0 + d)


class Matcher:
    """Algorithm 1 over one :class:`BimIndex`, one detected feature at a time."""

    def __init__(self, index: BimIndex, params: MatchParams) -> None:
        self.index = index
        self.params = params

    def match(
        self, s_xy: np.ndarray, s_cls: Sequence[str], s_travel: Sequence[float] | np.ndarray | None = None
    ) -> MatchState:
        """Run Algorithm 1 on the whole detected sequence S_object (``s_travel``: m of odometry travel
        at each feature's confirmation, for the landmarks' drift allowance; None: zeros)."""
        state = MatchState.empty()
        xy = np.asarray(s_xy, dtype=float).reshape(-1, 2)
        travel = np.zeros(len(xy)) if s_travel is None else np.asarray(s_travel, dtype=float)
        for p, cls, d in zip(xy, s_cls, travel, strict=True):
            state = self.extend(state, p, cls, float(d))
        return state

    def _alpha(self, state: MatchState, i: int, travel: float, lidar: bool) -> float:
        """The Eq. 7 threshold between s_i and the feature at ``travel`` (a landmark if ``lidar``):
        the camera's alpha, or between two landmarks the landmark alpha plus the drift allowance."""
        lm = self.params.landmarks
        assert state.s_lidar is not None and state.s_travel is not None
        if lm is None or not (lidar and state.s_lidar[i]):
            return self.params.alpha
        # the drift allowance never makes two landmarks looser than the camera's threshold
        return min(
            lm.alpha + lm.drift * abs(travel - float(state.s_travel[i])), max(self.params.alpha, lm.alpha)
        )

    def extend(self, state: MatchState, xy: np.ndarray, cls: str, travel: float = 0.0) -> MatchState:
        """Add detected feature s_n (the next in S_object) to every partial match of ``state``."""
        p = self.params
        n = state.n
        lidar = p.is_landmark(cls)
        assert state.s_lidar is not None and state.s_travel is not None
        s_xy = np.vstack([state.s_xy, np.asarray(xy, dtype=float).reshape(1, 2)])
        s_travel = np.append(state.s_travel, travel)
        s_lidar = np.append(state.s_lidar, lidar)
        s_new = s_xy[n]
        parts: list[dict[str, np.ndarray]] = []

        anchored = lidar and p.landmarks is not None and p.landmarks.anchored
        assert state.n_lm is not None
        # rows a landmark may join (anchored: those holding two camera features)
        open_rows = (state.n_in - state.n_lm >= 2) if anchored else True

        # -- rows with >= 2 inliers: the triple criteria of Eq. 9 (Algorithm 1, lines 7-12) ------
        tri = np.flatnonzero((state.n_in >= 2) & open_rows)
        if len(tri):
            keys = state.last2[tri] * (n + 1) + state.last1[tri]
            for key in np.unique(keys):
                rows = tri[keys == key]
                a, b = int(state.last2[rows[0]]), int(state.last1[rows[0]])
                alpha_ab = self._alpha(state, a, float(state.s_travel[b]), bool(state.s_lidar[b]))
                alpha_an = self._alpha(state, a, travel, lidar)
                part = self._extend_triples(state, rows, a, b, s_xy, cls, alpha_ab, alpha_an)
                if part is not None:
                    parts.append(part)

        # -- rows with 1 inlier: the pair criterion of Eq. 7 (Algorithm 1, lines 3-5) --------------
        one = np.flatnonzero((state.n_in == 1) & open_rows)
        if len(one):
            for a in np.unique(state.last1[one]):
                rows = one[state.last1[one] == a]
                alpha = self._alpha(state, int(a), travel, lidar)
                part = self._extend_pairs(state, rows, int(a), s_xy[int(a)], s_new, cls, alpha)
                if part is not None:
                    parts.append(part)

        # -- rows with no inlier yet: s_n starts a candidate (Algorithm 1, line 1) ----------------
        zero = np.flatnonzero(state.n_in == 0)
        members = self.index.class_members(cls)
        if anchored:
            members = members[:0]  # an anchored landmark never starts a candidate
        if len(zero) and len(members):
            r = np.repeat(zero, len(members))
            w = np.tile(members, len(zero))
            base = _rows(state, r)
            base["assign"] = np.column_stack([base["assign"], w])
            base["n_in"] = base["n_in"] + 1
            base["last2"] = base["last1"].copy()
            base["last1"] = np.full(len(r), n, dtype=np.intp)
            parts.append(base)
        if lidar:
            for part in parts:
                part["n_lm"] = part["n_lm"] + 1

        # -- outlier tolerance: s_n treated as a false/misclassified detection (a landmark: as
        # geometry the BIM lacks, within the landmarks' own budget) ---------------------------------
        if lidar:
            assert p.landmarks is not None and state.n_lm_out is not None
            out = np.flatnonzero(state.n_lm_out < p.landmarks.budget(int(s_lidar.sum())))
        else:
            out = np.flatnonzero(state.n_out < p.max_outliers)
        if len(out):
            base = _rows(state, out)
            base["assign"] = np.column_stack([base["assign"], np.full(len(out), OUTLIER, dtype=np.intp)])
            if lidar:
                base["n_lm_out"] = base["n_lm_out"] + 1
            else:
                base["n_out"] = base["n_out"] + 1
            parts.append(base)

        return self._assemble(parts, s_xy, [*state.s_cls, cls], n + 1, s_travel, s_lidar)

    def _assemble(
        self,
        parts: list[dict[str, np.ndarray]],
        s_xy: np.ndarray,
        s_cls: list[str],
        n: int,
        s_travel: np.ndarray,
        s_lidar: np.ndarray,
    ) -> MatchState:
        total = sum(len(part["cost"]) for part in parts)
        if total > self.params.max_partials:
            raise MatchOverflow(f"{total} partial matches exceed the cap of {self.params.max_partials}")
        if not parts:
            empty = np.zeros(0, dtype=np.intp)
            return MatchState(
                s_xy,
                s_cls,
                np.zeros((0, n), dtype=np.intp),
                empty,
                empty.copy(),
                empty.copy(),
                empty.copy(),
                np.zeros(0),
                s_travel=s_travel,
                s_lidar=s_lidar,
            )
        joined = {name: np.concatenate([part[name] for part in parts]) for name in _ROW_FIELDS}
        joined["assign"] = joined["assign"].astype(np.intp, copy=False)
        return MatchState(s_xy=s_xy, s_cls=s_cls, s_travel=s_travel, s_lidar=s_lidar, **joined)

    def _extend_pairs(
        self,
        state: MatchState,
        rows: np.ndarray,
        a: int,
        s_a: np.ndarray,
        s_new: np.ndarray,
        cls: str,
        alpha: float,
    ) -> dict[str, np.ndarray] | None:
        b_xy = self.index.xy
        d_s = float(pair_distance(s_a, s_new))  # d^S_{12} (Eq. 5 in the odom frame)
        u = state.assign[rows, a]
        q, w = self.index.ball(b_xy[u], cls, d_s + alpha)
        if len(q) == 0:
            return None
        d_b = pair_distance(b_xy[u[q]], b_xy[w])  # Eq. 5
        err = np.abs(d_b - d_s)
        ok = (err <= alpha) & (w != u[q])  # Eq. 7, b_v != b_u
        if not ok.any():
            return None
        q, w, err = q[ok], w[ok], err[ok]
        base = _rows(state, rows[q])
        base["assign"] = np.column_stack([base["assign"], w])
        base["n_in"] = base["n_in"] + 1
        base["last2"] = np.full(len(q), a, dtype=np.intp)
        base["last1"] = np.full(len(q), state.n, dtype=np.intp)
        base["cost"] = base["cost"] + err  # Eq. 14, first term
        return base

    def _extend_triples(
        self,
        state: MatchState,
        rows: np.ndarray,
        a: int,
        b: int,
        s_xy: np.ndarray,
        cls: str,
        alpha_ab: float,
        alpha_an: float,
    ) -> dict[str, np.ndarray] | None:
        beta = self.params.beta
        n = state.n
        b_xy = self.index.xy
        s_a, s_b, s_n = s_xy[a], s_xy[b], s_xy[n]
        d_ab = float(pair_distance(s_a, s_b))  # d^S_{i-2,i-1}
        d_an = float(pair_distance(s_a, s_n))  # d^S_{i-2,i}
        th_s = float(rotation_angle(s_a, s_b, s_n))  # theta_{i-2,i-1,i} (Eq. 8, odom frame)

        u = state.assign[rows, a]
        v = state.assign[rows, b]
        bu, bv = b_xy[u], b_xy[v]
        d_uv = pair_distance(bu, bv)
        err_uv = np.abs(d_uv - d_ab)
        ok = err_uv <= alpha_ab  # Eq. 9, first condition: z_d({s_{i-2}, b_u}, {s_{i-1}, b_v}) = 1
        if not ok.any():
            return None
        rows, u, bu, bv, d_uv, err_uv = rows[ok], u[ok], bu[ok], bv[ok], d_uv[ok], err_uv[ok]

        # Predicted b_w: at distance d^S_{i-2,i} from b_u, rotated theta_ijk from b_u->b_v.
        c, s = math.cos(th_s), math.sin(th_s)
        safe = np.where(d_uv > 0.0, d_uv, 1.0)
        dx, dy = (bv[:, 0] - bu[:, 0]) / safe, (bv[:, 1] - bu[:, 1]) / safe
        pred = bu + d_an * np.column_stack([c * dx - s * dy, s * dx + c * dy])
        radius = _sector_radius(d_an, alpha_an, beta)
        degenerate = d_uv <= 0.0  # coincident BIM features: direction undefined, search the disc
        if degenerate.any():
            pred[degenerate] = bu[degenerate]
            radius = max(radius, d_an + alpha_an + 1e-9)
        q, w = self.index.ball(pred, cls, radius)
        if len(q) == 0:
            return None

        bw = b_xy[w]
        err_uw = np.abs(pair_distance(bu[q], bw) - d_an)
        err_th = angle_difference(rotation_angle(bu[q], bv[q], bw), th_s)
        ok = (err_uw <= alpha_an) & (err_th <= beta)  # Eq. 9, second and third conditions
        if not ok.any():
            return None
        q, w, err_uw, err_th = q[ok], w[ok], err_uw[ok], err_th[ok]
        if self.params.revisits:
            # Revisits: a BIM feature may be matched again by a later detection (the robot came back
            # and odometry drift kept the filter from merging the two); a triple still needs three
            # distinct BIM features.
            used = (w == u[q]) | (w == state.assign[rows[q], b])
        else:
            used = (state.assign[rows[q]] == w[:, None]).any(axis=1)  # "w not matched with any feature"
        if used.all():
            return None
        keep = ~used
        q, w, err_uw, err_th = q[keep], w[keep], err_uw[keep], err_th[keep]

        base = _rows(state, rows[q])
        base["assign"] = np.column_stack([base["assign"], w])
        base["n_in"] = base["n_in"] + 1
        base["last2"] = np.full(len(q), b, dtype=np.intp)
        base["last1"] = np.full(len(q), n, dtype=np.intp)
        base["cost"] = base["cost"] + err_uv[q] + err_uw + err_th  # Eq. 14, one summand
        return base


def match_sequence(
    index: BimIndex, s_xy: np.ndarray, s_cls: Sequence[str], params: MatchParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Convenience: the complete matches of S_object as (assign (H, n), n_out (H,), cost (H,))."""
    matcher = Matcher(index, params)
    state = matcher.match(s_xy, s_cls)
    rows = state.matches(matcher.params)
    return state.assign[rows], state.n_out[rows], state.cost[rows]
