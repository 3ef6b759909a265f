"""How much a pose rests on one part of its scan (beyond the paper): a jackknife over the scan's
sectors.

A particle filter (Eq. 18) weighs every beam as independent evidence, so its spread says how well
the scan *as a whole* pins the pose. When one part of the scan ends on something the map lacks or
draws elsewhere (a hoarding half a metre in front of a drawn wall), the whole cloud moves with it
and stays tight. Re-fitting the pose with a part of the scan left out shows it: the fits that lack
the misleading part land elsewhere. The scan's valid beams are cut by bearing into K sectors; each
fit ``p_k`` (x, y, yaw) leaves out a window of adjacent sectors starting at sector k (a hoarding
seen from a few metres spans more than one), and their spread becomes a covariance,

    J = (K - d) / (d K) * sum_k (p_k - p_mean) (p_k - p_mean)^T

for windows of d sectors (the block jackknife's factor; (K - 1) / K for d = 1). Each fit is
local: the beam end points moved to the map's distance field (the end-point model of Eq. 18, each
beam's distance capped so that clutter weighs the same wherever it stands). Pure numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from initcli.core.filters.particle_filter import LikelihoodField, valid_beams
from initcli.core.geometry.se2 import Pose2D

__all__ = ["JackknifeParams", "fit_scan_locally", "sector_jackknife"]


@dataclass(frozen=True)
class JackknifeParams:
    """The local fit and the sectors of :func:`sector_jackknife`."""

    sectors: int = 8  # contiguous groups of valid beams, by bearing
    left_out: int = 2  # adjacent sectors left out together (a quarter of the scan), each window in turn
    # m: a beam end's distance to the map counts up to this; twice the scan tolerance, so that a fit
    # that lost the part of the scan it followed reaches the walls the rest sees half a metre away
    reach: float = 0.5
    step: float = 0.1  # m: the local fit's first shift (the turn: step / turn_radius radians)
    min_step: float = 0.0125  # m: the local fit stops below this
    turn_radius: float = 5.0  # m: a turn of step / turn_radius moves a beam end this far away by step
    max_moves: int = 80  # moves of the local fit at most
    min_beams: int = 24  # fewer valid beams: no jackknife (zero)


_UNIT = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)], dtype=float)
_UNIT = _UNIT[np.argsort(np.abs(_UNIT).sum(axis=1), kind="stable")]  # the centre first: ties stay put


def _cost(
    poses: np.ndarray, bx: np.ndarray, by: np.ndarray, field: LikelihoodField, cap: float
) -> np.ndarray:
    """Sum over the beam ends (``bx``, ``by`` in the robot frame) of their capped squared distance to
    the map, for each of ``poses`` (M, 3)."""
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    ex = poses[:, 0:1] + c * bx[None, :] - s * by[None, :]
    ey = poses[:, 1:2] + s * bx[None, :] + c * by[None, :]
    d = np.minimum(field.interpolated(ex, ey), cap)
    cost: np.ndarray = (d * d).sum(axis=1)
    return cost


def fit_scan_locally(
    pose: Pose2D,
    bx: np.ndarray,
    by: np.ndarray,
    field: LikelihoodField,
    params: JackknifeParams,
) -> np.ndarray:
    """The pose near ``pose`` (x, y, yaw) whose beam ends (``bx``, ``by``, robot frame) lie nearest the
    map's walls, each distance counted up to ``params.reach``: a pattern search over shifts and turns,
    the step halved whenever no neighbour is better (a flat direction, a corridor's length, is not
    moved along)."""
    p = np.array([pose.x, pose.y, pose.yaw])
    step = params.step
    for _ in range(params.max_moves):
        scale = np.array([step, step, step / params.turn_radius])
        tries = p[None, :] + _UNIT * scale[None, :]
        costs = _cost(tries, bx, by, field, params.reach)
        best = int(np.argmin(costs))  # the first of equals: the centre when nothing is better
        if best == 0:
            step /= 2.0
            if step < params.min_step:
                break
            continue
        p = tries[best]
    return p


def sector_jackknife(
    pose: Pose2D,
    angles: np.ndarray,
    ranges: np.ndarray,
    range_max: float,
    field: LikelihoodField,
    params: JackknifeParams | None = None,
) -> np.ndarray:
    """``J`` of the module docstring (3x3, x, y, yaw) for a scan seen from ``pose``: zero for a scan
    of too few valid beams."""
    params = params or JackknifeParams()
    ok = valid_beams(ranges, range_max)
    if int(ok.sum()) < max(params.min_beams, 2 * params.sectors):
        return np.zeros((3, 3))
    bearing, r = np.asarray(angles, dtype=float)[ok], np.asarray(ranges, dtype=float)[ok]
    order = np.argsort(np.mod(bearing, math.tau), kind="stable")
    bx, by = (r * np.cos(bearing))[order], (r * np.sin(bearing))[order]
    whole = fit_scan_locally(pose, bx, by, field, params)
    start = Pose2D(float(whole[0]), float(whole[1]), float(whole[2]))
    sector = np.zeros(len(bx), dtype=np.intp)
    for i, group in enumerate(np.array_split(np.arange(len(bx)), params.sectors)):
        sector[group] = i
    fits = []
    for first in range(params.sectors):
        keep = np.mod(sector - first, params.sectors) >= params.left_out  # a window of sectors out
        fits.append(fit_scan_locally(start, bx[keep], by[keep], field, params))
    rel = np.array(fits) - whole  # about the whole scan's fit, the turn wrapped, then centred
    rel[:, 2] = np.remainder(rel[:, 2] + math.pi, math.tau) - math.pi
    dev = rel - rel.mean(axis=0)
    k, d = len(fits), params.left_out
    jack: np.ndarray = (k - d) / (d * k) * (dev.T @ dev)
    return jack
