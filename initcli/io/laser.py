"""Planar laser scans and odometry as the detection log keeps them, from any source (a ROS bag, a
CARMEN log): the scan's geometry checked, its no-returns made NaN, the scan carried from the laser's
mount into the robot's base frame, and the odometry checked for jumps and interleaved publishers.

A ``scan`` record is in the robot's base frame: its beams start at the base origin, angle 0 along the
base's x axis (the simulator's lidar sits there). A laser mounted elsewhere is carried there: a turn
(any yaw, or upside down) by shifting the angles, exactly; an offset by re-binning each return at
its bearing and range from the base origin on a grid of the scan's own angle increment (each bin
keeps its nearest return).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from bimkit.errors import InputError
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.io.log_records import Scan

__all__ = [
    "MAX_ODOM_STEP_M",
    "MOUNT_OFFSET_M",
    "check_odometry",
    "check_scan_geometry",
    "no_returns",
    "scan_in_base",
]

MOUNT_OFFSET_M = 1e-3  # m: a laser this close to the base origin is taken as on it (no re-binning)
MAX_ODOM_STEP_M = 20.0  # m between consecutive odometry poses: more is a broken record, not motion
INTERLEAVED_RATIO = 3.0  # path along every sample over that along every other one: two publishers


def check_scan_geometry(
    where: str, n: int, angle_min: float, angle_increment: float, span: float | None
) -> None:
    """InputError naming ``where`` when the angles are not finite, the increment is 0, or the number
    of ranges disagrees with the span (``span``: angle_max - angle_min, or the field of view; None:
    not given). A count of span/increment or span/increment + 1 both pass (drivers differ)."""
    if not (math.isfinite(angle_min) and math.isfinite(angle_increment)):
        raise InputError(f"{where}: a scan's angle_min or angle_increment is not finite")
    if abs(angle_increment) < 1e-9:
        raise InputError(f"{where}: a scan's angle increment is 0")
    if abs(angle_increment) * max(n - 1, 0) > 2 * math.pi + abs(angle_increment) + 1e-6:
        raise InputError(
            f"{where}: a scan of {n} ranges {math.degrees(abs(angle_increment)):g} deg apart spans more "
            "than a full turn"
        )
    if span is None or n == 0:
        return
    if not math.isfinite(span):
        raise InputError(f"{where}: a scan's angle span is not finite")
    steps = span / angle_increment
    if steps < -0.5 or not (steps - 1.5 <= n - 1 <= steps + 1.5):
        raise InputError(
            f"{where}: a scan's {n} ranges disagree with its angles ({math.degrees(span):g} deg at "
            f"{math.degrees(angle_increment):g} deg a beam is {int(round(steps)) + 1} ranges)"
        )


def no_returns(ranges: np.ndarray, range_min: float, range_max: float) -> np.ndarray:
    """``ranges`` with every no-return as NaN: inf, NaN, 0 or less, below ``range_min``, at or above
    ``range_max``."""
    r = np.asarray(ranges, dtype=float)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r > 0) & (r >= range_min) & (r < range_max)
    return np.where(ok, r, math.nan)


def scan_in_base(
    t: float,
    angle_min: float,
    angle_increment: float,
    range_max: float,
    ranges: np.ndarray,
    mount: Pose2D | None = None,
    flipped: bool = False,
) -> Scan:
    """A scan (no-returns already NaN) of a laser at ``mount`` on the base (``flipped``: mounted
    upside down, its angles counted clockwise seen from above) as a ``scan`` record in the base frame."""
    r = np.asarray(ranges, dtype=float)
    sign = -1.0 if flipped else 1.0
    yaw = mount.yaw if mount is not None else 0.0
    if mount is None or math.hypot(mount.x, mount.y) < MOUNT_OFFSET_M:
        if flipped:  # counted clockwise: reverse the beams so the increment stays positive
            last = angle_min + angle_increment * max(len(r) - 1, 0)
            start, step, r = yaw - last, angle_increment, r[::-1]
        else:
            start, step = yaw + angle_min, angle_increment
        if step < 0:  # a scanner counting down: its beams in increasing angle
            start, step, r = start + step * max(len(r) - 1, 0), -step, r[::-1]
        return Scan(t, float(wrap_angle(start)), float(step), float(range_max), tuple(r.tolist()))
    return _rebinned(t, angle_min, angle_increment, range_max, r, mount, sign)


def _rebinned(
    t: float, angle_min: float, inc: float, range_max: float, r: np.ndarray, mount: Pose2D, sign: float
) -> Scan:
    """Each return at its bearing and range from the base origin, on a grid of ``|inc|``."""
    n = len(r)
    step = abs(inc)
    beams = angle_min + inc * np.arange(n)
    bearing_laser = mount.yaw + sign * beams  # in the base frame, from the laser
    centre = float(mount.yaw + sign * (angle_min + inc * (n - 1) / 2.0))
    full = step * n >= 2 * math.pi - 1.5 * step
    if full:
        bins = int(round(2 * math.pi / step))
        lo = centre - math.pi
    else:
        edge = np.abs(wrap_angle(bearing_laser - centre)).max() if n else 0.0
        # an offset laser sees a little wider or narrower from the base: a margin of a few bins
        margin = math.atan2(math.hypot(mount.x, mount.y), 0.5) + 2 * step
        half = min(float(edge) + margin, math.pi)
        bins = int(math.ceil(2 * half / step)) + 1
        lo = centre - half
    out = np.full(bins, math.inf)
    ok = np.isfinite(r)
    x = mount.x + r[ok] * np.cos(bearing_laser[ok])
    y = mount.y + r[ok] * np.sin(bearing_laser[ok])
    dist = np.hypot(x, y)
    bearing = np.arctan2(y, x)
    if full:
        idx = np.rint(np.mod(bearing - lo, 2 * math.pi) / step).astype(int) % bins
    else:
        idx = np.rint((wrap_angle(bearing - centre) - (lo - centre)) / step).astype(int)
    keep = (idx >= 0) & (idx < bins)
    np.minimum.at(out, idx[keep], dist[keep])
    out[~np.isfinite(out)] = math.nan
    reach = range_max + math.hypot(mount.x, mount.y)
    return Scan(t, float(wrap_angle(lo)), float(step), float(reach), tuple(out.tolist()))


def check_odometry(
    where: str, times: Sequence[float], xy: np.ndarray, labels: Sequence[str] | None = None
) -> None:
    """InputError when one odometry pose jumps more than :data:`MAX_ODOM_STEP_M` from the one before
    (naming ``labels[i]``, else the stamp), or when the poses zigzag between two tracks (two
    publishers interleaved on one topic: the path along every pose is many times that along every
    other one)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy) < 2:
        return
    steps = np.hypot(*np.diff(xy, axis=0).T)
    bad = np.flatnonzero(steps > MAX_ODOM_STEP_M)
    if bad.size:
        j = int(bad[0])  # the step from pose j to pose j + 1; the first pose may be the odd one out
        i = 0 if j == 0 and len(steps) > 1 and steps[1] <= MAX_ODOM_STEP_M else j + 1
        at = labels[i] if labels is not None else f"t={times[i]:.3f} s"
        side = "after" if i == 0 else "before"
        raise InputError(
            f"{where}: an odometry pose {steps[j]:.1f} m from the one {side} ({at}; at most "
            f"{MAX_ODOM_STEP_M:g} m between two): a broken record"
        )
    if len(xy) < 8:
        return
    every = float(steps.sum())
    other = max(float(np.hypot(*np.diff(xy[k::2], axis=0).T).sum()) for k in (0, 1))
    if every > INTERLEAVED_RATIO * other + 1.0:
        raise InputError(
            f"{where}: the odometry zigzags between two tracks ({every:.1f} m along every pose, "
            f"{other:.1f} m along every other one): two publishers interleaved? record one"
        )
