"""The lidar's fit of a pose (beyond the paper): the share of the beam end points of some scans,
put into the BIM frame by a transform, that land near the BIM's walls (the beam end-point model of
the fine-tuning filter, Eq. 18, with no beam skipped), and the best such fit over small shifts and
turns of that transform (the lidar's correction of a coarse pose). Pure numpy; the session and
``bim-init match`` gather the scans, :mod:`initcli.core.verify.checks` judges with them."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from initcli.core.filters.particle_filter import LikelihoodField, valid_beams
from initcli.core.geometry.se2 import Pose2D

__all__ = ["AlignmentMoves", "BeamEnds", "SCAN_TURN_STEP_DEG", "ScanSample", "best_scan_alignment"]

SCAN_TURN_STEP_DEG = 3.0  # degrees between the turns best_scan_alignment tries


@dataclass(frozen=True)
class ScanSample:
    """One lidar scan in the odometry frame: the robot's odom pose and its beams."""

    odom: Pose2D
    angles: np.ndarray
    ranges: np.ndarray
    range_max: float

    def thinned(self, step: int) -> ScanSample:
        """The scan with every ``step`` th beam."""
        return ScanSample(self.odom, self.angles[::step], self.ranges[::step], self.range_max)


@dataclass(frozen=True)
class BeamEnds:
    """Every valid beam end point of some scans once, in the frame of the robot at the last scan,
    scan after scan: what :func:`best_scan_alignment` moves around."""

    last: Pose2D  # odom pose of the last scan
    xy: np.ndarray  # (N, 2) end points in the last scan's robot frame, the scans' points one after another
    valid: np.ndarray  # (scans,) valid beams per scan
    origins: np.ndarray | None = None  # (scans, 2) where each scan was taken, in the same frame

    @staticmethod
    def of(scans: list[ScanSample]) -> BeamEnds:
        last = scans[-1].odom
        back = last.inverse()
        points = []
        valid = np.zeros(len(scans))
        origins = np.zeros((len(scans), 2))
        for i, scan in enumerate(scans):
            ok = valid_beams(scan.ranges, scan.range_max)
            rel = back * scan.odom
            origins[i] = rel.x, rel.y
            heading = rel.yaw + scan.angles[ok]
            r = scan.ranges[ok]
            points.append(np.column_stack([rel.x + r * np.cos(heading), rel.y + r * np.sin(heading)]))
            valid[i] = len(r)
        return BeamEnds(last, np.vstack(points), valid, origins)

    def beam_origins(self) -> np.ndarray:
        """(N, 2): where the scan of each end point was taken (needs ``origins``)."""
        assert self.origins is not None
        return np.repeat(self.origins, self.valid.astype(np.intp), axis=0)

    @functools.cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Each scan's first and one-past-last point index in ``xy``."""
        stop = np.cumsum(self.valid.astype(np.intp))
        return stop - self.valid.astype(np.intp), stop


@dataclass(frozen=True)
class AlignmentMoves:
    """The moves :func:`best_scan_alignment` tries, nearest first (so that a tie keeps the smallest
    correction): each a turn and an x and y shift, and their indices in ``turns`` and ``shifts``."""

    turns: np.ndarray
    shifts: np.ndarray
    moves: tuple[tuple[float, float, float], ...]  # (turn, dx, dy)
    turn: np.ndarray  # (moves,) index into turns
    ix: np.ndarray  # (moves,) index of dx into shifts
    iy: np.ndarray


@functools.lru_cache(maxsize=64)
def _alignment_moves(
    search_xy: float, search_yaw: float, shift_steps: int, turn_step_deg: float
) -> AlignmentMoves:
    shifts = np.linspace(-search_xy, search_xy, shift_steps) if search_xy > 0 else np.zeros(1)
    steps = 2 * math.ceil(search_yaw / math.radians(turn_step_deg)) + 1
    turns = np.linspace(-search_yaw, search_yaw, steps) if search_yaw > 0 else np.zeros(1)
    grid = [
        ((float(a), float(dx), float(dy)), (t, i, j))
        for t, a in enumerate(turns)
        for i, dx in enumerate(shifts)
        for j, dy in enumerate(shifts)
    ]
    grid.sort(
        key=lambda m: (
            abs(m[0][0]) / max(search_yaw, 1e-9) + math.hypot(m[0][1], m[0][2]) / max(search_xy, 1e-9)
        )
    )
    at = np.array([index for _, index in grid], dtype=np.intp).reshape(-1, 3)
    return AlignmentMoves(turns, shifts, tuple(move for move, _ in grid), at[:, 0], at[:, 1], at[:, 2])


def best_scan_alignment(
    transform: Pose2D,
    scans: list[ScanSample] | BeamEnds,
    field_: LikelihoodField,
    tolerance: float,
    search_xy: float = 0.0,
    search_yaw: float = 0.0,
    shift_steps: int = 5,
    turn_step_deg: float = SCAN_TURN_STEP_DEG,
) -> tuple[float, Pose2D] | None:
    """The best mean share of beams on mapped walls over ``scans``, each placed in the BIM frame by
    ``transform`` (odom -> BIM) moved by a ``shift_steps`` x ``shift_steps`` grid of shifts (up to
    ``search_xy`` m) and turns in steps of at most ``turn_step_deg`` degrees (up to ``search_yaw``
    rad) of the pose at the last scan, and the moved transform that fits best (the lidar's
    correction of a coarse pose). None when there is no scan."""
    if not scans:
        return None
    ends = scans if isinstance(scans, BeamEnds) else BeamEnds.of(scans)
    here = transform * ends.last
    moves = _alignment_moves(search_xy, search_yaw, shift_steps, turn_step_deg)
    # A move turns and shifts the end points all together. A shift moves every point's column (x)
    # or row (y) alone: each is found once per turn and shift value, and all the moves' cells are
    # looked up at once in the boolean map of cells within the tolerance.
    xy = ends.xy
    c = np.array([math.cos(here.yaw + a) for a in moves.turns])[:, None]
    s_ = np.array([math.sin(here.yaw + a) for a in moves.turns])[:, None]
    ex, ey = here.x + c * xy[:, 0] - s_ * xy[:, 1], here.y + s_ * xy[:, 0] + c * xy[:, 1]  # (turns, points)
    cols = field_.padded_col(ex[:, None, :] + moves.shifts[None, :, None])  # (turns, shift values, points)
    rows = field_.padded_row(ey[:, None, :] + moves.shifts[None, :, None]) * (field_.cols + 2)
    on_wall = field_.near_walls(tolerance)[rows[moves.turn, moves.iy] + cols[moves.turn, moves.ix]]
    # Beams on walls per move and scan: a running count along each move's points, read at the scans'
    # bounds (whole numbers: exact; a matrix product would do the same through a threaded BLAS).
    running = np.zeros((len(on_wall), len(xy) + 1), dtype=np.int32)
    np.cumsum(on_wall, axis=1, dtype=np.int32, out=running[:, 1:])
    first, stop = ends.bounds
    # (moves, scans), C order as the mean below must sum each row as it always has (column indexing
    # returns Fortran order: its row sums round differently)
    hits = np.ascontiguousarray(running[:, stop] - running[:, first], dtype=float)
    valid = ends.valid[None, :]
    share = np.divide(hits, valid, out=np.zeros_like(hits), where=valid > 0)
    fits = share.mean(axis=1)
    k = int(np.argmax(fits))  # the first of the best: the nearest move
    dyaw, dx, dy = moves.moves[k]
    return float(fits[k]), Pose2D(here.x + dx, here.y + dy, here.yaw + dyaw) * ends.last.inverse()
