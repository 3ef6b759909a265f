"""Kidnaps spliced from a real laser log, and controls, for ``bench_watch``.

A **kidnap** joins two stretches of one log (:func:`kidnap`): the robot drives the first stretch,
is carried (its wheels unaware) and drives the second. Its odometry runs on from the first
stretch's end with the second stretch's motion (drifting, :data:`_real_lidar.DRIFT`); its scans are
the second stretch's; the localiser's pose is right on the first stretch (the truth, with a little
noise) and after the splice carried on by odometry from where the first stretch ended, as a
tracking localiser that did not notice follows its odometry. A **control** (:func:`control`) is one
stretch whose localiser pose stays right.

Both are detection logs (``localiser`` records included) and their truth over time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from _real_lidar import DRIFT, Drift, LogTruth, drift_scales, drifted_poses

from initcli.core.geometry.se2 import Pose2D
from initcli.io.log_records import Localiser, Meta, Odom, Scan

__all__ = ["Case", "LOCALISER_NOISE", "control", "kidnap", "stretch"]

LOCALISER_NOISE = (0.05, math.radians(1.0))  # m, rad: sd of a right localiser's own error
GAP_S = 0.1  # s between the first stretch's last record and the second's first


@dataclass
class Case:
    kind: str  # "kidnap" or "control"
    records: list[Meta | Odom | Scan | Localiser]
    truth_t: np.ndarray  # the robot's true pose over time: stamps ...
    truth: np.ndarray  # ... (N, 3) x, y, yaw (unwrapped), the log's map frame
    splice_t: float | None  # the kidnap's time (None: a control)
    splice_travel: float | None  # m of odometry travel then

    def truth_at(self, t: float) -> Pose2D:
        x = float(np.interp(t, self.truth_t, self.truth[:, 0]))
        y = float(np.interp(t, self.truth_t, self.truth[:, 1]))
        return Pose2D(x, y, float(np.interp(t, self.truth_t, self.truth[:, 2])))


def stretch(truth: LogTruth, start: float, length: float) -> tuple[int, int] | None:
    """Scans (first, last) of ``length`` m of travel from ``start`` m (None past the log's end)."""
    i = int(np.searchsorted(truth.travel, start))
    j = int(np.searchsorted(truth.travel, start + length))
    return (i, j) if j < len(truth.scans) else None


def _odom(truth: LogTruth, first: int, last: int) -> list[Odom]:
    t0, t1 = truth.scans[first].t, truth.scans[last].t
    return [o for o in truth.odom if t0 <= o.t <= t1]


def _noisy(pose: Pose2D, rng: np.random.Generator) -> Pose2D:
    m, rad = LOCALISER_NOISE
    return Pose2D(pose.x + rng.normal(0, m), pose.y + rng.normal(0, m), pose.yaw + rng.normal(0, rad))


def kidnap(
    truth: LogTruth, a: tuple[int, int], b: tuple[int, int], rng: np.random.Generator, drift: Drift = DRIFT
) -> Case:
    """The stretch of scans ``a`` then, carried, the stretch ``b`` (module docstring)."""
    scale, turn = drift_scales(drift, rng)
    odom_a, odom_b = _odom(truth, *a), _odom(truth, *b)
    shift = odom_a[-1].t + GAP_S - odom_b[0].t
    drift_a = drifted_poses(odom_a, odom_a[0].pose, drift, rng, scale, turn)
    drift_b = drifted_poses(odom_b, drift_a[-1], drift, rng, scale, turn)  # the wheels felt nothing
    stale = odom_a[-1].pose * drift_a[-1].inverse()  # the localiser's odom -> map when carried
    records: list[Meta | Odom | Scan | Localiser] = [truth.meta]
    for o, d in zip(odom_a, drift_a, strict=True):
        records.append(Odom(o.t, d.x, d.y, d.yaw))
        seen = _noisy(o.pose, rng)
        records.append(Localiser(o.t, seen.x, seen.y, seen.yaw))
    for o, d in zip(odom_b, drift_b, strict=True):
        records.append(Odom(o.t + shift, d.x, d.y, d.yaw))
        carried = stale * d
        records.append(Localiser(o.t + shift, carried.x, carried.y, carried.yaw))
    records += [s for s in truth.scans[a[0] : a[1] + 1]]
    records += [
        Scan(s.t + shift, s.angle_min, s.angle_increment, s.range_max, s.ranges)
        for s in truth.scans[b[0] : b[1] + 1]
    ]
    body = sorted(records[1:], key=lambda r: r.t)  # type: ignore[union-attr]
    true_t = np.array([o.t for o in odom_a] + [o.t + shift for o in odom_b])
    poses = np.array([[o.x, o.y, o.yaw] for o in odom_a + odom_b])
    poses[:, 2] = np.unwrap(poses[:, 2])
    splice_travel = float(truth.travel[a[1]] - truth.travel[a[0]])
    return Case("kidnap", [truth.meta, *body], true_t, poses, odom_a[-1].t, splice_travel)


def control(truth: LogTruth, a: tuple[int, int], rng: np.random.Generator, drift: Drift = DRIFT) -> Case:
    """The stretch ``a`` with the localiser's pose right all along (a little noise)."""
    scale, turn = drift_scales(drift, rng)
    odom_a = _odom(truth, *a)
    drift_a = drifted_poses(odom_a, odom_a[0].pose, drift, rng, scale, turn)
    records: list[Meta | Odom | Scan | Localiser] = []
    for o, d in zip(odom_a, drift_a, strict=True):
        records.append(Odom(o.t, d.x, d.y, d.yaw))
        seen = _noisy(o.pose, rng)
        records.append(Localiser(o.t, seen.x, seen.y, seen.yaw))
    records += list(truth.scans[a[0] : a[1] + 1])
    body = sorted(records, key=lambda r: r.t)  # type: ignore[union-attr]
    poses = np.array([[o.x, o.y, o.yaw] for o in odom_a])
    poses[:, 2] = np.unwrap(poses[:, 2])
    return Case("control", [truth.meta, *body], np.array([o.t for o in odom_a]), poses, None, None)
