"""Where a session's lidar registration places a survey start (beyond the paper).

A session without a camera claim registers the submap of its last ``registration.window`` m every
``registration.every`` m (:func:`initcli.core.lidar.registration.register`). The survey does the
same along each wall-following loop, noise-free: a scan every ``TRACK_STEP_M`` m of the loop
(ray-cast against the obstacle outlines with every door leaf closed, as the simulated world stands),
the last quarter, half and whole window before each registration point registered over the
storey's map (a session's submap is the path so far until it has driven a window). A point is
*placed* where that registration is unique and right (within ``RIGHT_M`` and ``RIGHT_DEG`` of the
loop's pose): a unique place elsewhere is a wrong claim the session's checks must catch, not a
start placed. A start is placed by the lidar at the first point it reaches along its loop that the
longest submap it has driven places (the loop's metres before the point standing for the start's
own path), so the survey's distance is an upper bound where the start's first scans, turning on the
spot, are unique already.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.raycast import cast_rays
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.registration import RegistrationMap, register
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.scan_fit import BeamEnds, ScanSample
from initcli.survey.exploration import Entry, Loop

__all__ = [
    "LidarModel",
    "LoopRegistration",
    "RIGHT_DEG",
    "RIGHT_M",
    "SUBMAP_FRACTIONS",
    "TRACK_STEP_M",
    "lidar_distances",
    "submap_lengths",
]

TRACK_STEP_M = 0.5  # m of the loop between two scans of the submap (the session keeps one per 0.5 m)
BEAM_STEP = 2  # every second beam of a scan, as the session's submap
RIGHT_M = 0.5  # m: a registration this close to the loop's pose is right ...
RIGHT_DEG = 5.0  # ... and turned at most this much
SUBMAP_FRACTIONS = (0.25, 0.5, 1.0)  # of registration.window: the submap lengths registered


@dataclass(frozen=True)
class LidarModel:
    """The session's lidar (``lidar:`` of site.yaml), noise-free."""

    beams: int = 360
    fov_deg: float = 360.0
    max_range: float = 20.0

    def angles(self) -> np.ndarray:
        fov = math.radians(self.fov_deg)
        full = self.fov_deg >= 360.0
        return -fov / 2 + np.arange(self.beams) * (fov / (self.beams if full else max(1, self.beams - 1)))


def _scan(pose: np.ndarray, lidar: LidarModel, angles: np.ndarray, segments: np.ndarray) -> ScanSample:
    ranges = cast_rays(pose[:2], pose[2] + angles, segments, lidar.max_range)
    ranges = np.where(ranges >= lidar.max_range, np.inf, ranges)  # no return
    return ScanSample(Pose2D(float(pose[0]), float(pose[1]), float(pose[2])), angles, ranges, lidar.max_range)


def submap_lengths(params: RegistrationParams) -> tuple[float, ...]:
    """The submap lengths the survey registers along a loop: a quarter, a half and the whole
    ``params.window`` (a session's submap is the path so far until it has driven a window)."""
    return tuple(params.window * f for f in SUBMAP_FRACTIONS)


@dataclass(frozen=True)
class LoopRegistration:
    """The session's registration along the survey's loops: scans ray-cast against ``segments``
    (every door leaf closed) registered on ``maps`` with ``params``; a point is placed where that
    registration is unique and right on ``storey``."""

    segments: np.ndarray
    maps: list[RegistrationMap]
    storey: str
    params: RegistrationParams
    tolerance: float
    lidar: LidarModel

    def points(self, loop: Loop) -> list[tuple[int, int]]:
        """The (submap level, loop point) pairs registered: every ``params.every`` m of the loop,
        per submap length of :func:`submap_lengths`; none without a map."""
        if not self.maps:
            return []
        every = max(1, int(round(self.params.every / loop.step)))
        levels = range(len(submap_lengths(self.params)))
        return [(level, at) for level in levels for at in range(0, len(loop), every)]

    def placed_at(self, loop: Loop, points: list[tuple[int, int]]) -> list[bool]:
        """Per (level, point) of ``points``: is the registration of that submap length of the loop
        before the point unique and right? Each is independent of the others, so a loop's points
        can be shared out."""
        n = len(loop)
        lengths = submap_lengths(self.params)
        keep = max(1, int(round(TRACK_STEP_M / loop.step)))
        angles = self.lidar.angles()[::BEAM_STEP]
        cache: dict[int, ScanSample] = {}
        out: list[bool] = []
        for level, at in points:
            span = min(n, max(1, int(round(lengths[level] / loop.step))))
            scans = []
            for i in ((at - k) % n for k in range(span - 1, -1, -keep)):
                if i not in cache:
                    cache[i] = _scan(loop.poses[i], self.lidar, angles, self.segments)
                scans.append(cache[i])
            found = register(BeamEnds.of(scans), self.maps, self.params, self.tolerance)
            best, truth = found.best, scans[-1].odom
            out.append(
                found.unique
                and best is not None
                and best.storey == self.storey
                and best.pose.distance_to(truth) <= RIGHT_M
                and best.pose.yaw_error(truth) <= math.radians(RIGHT_DEG)
            )
        return out

    def placed_from(self, loop: Loop, points: list[tuple[int, int]], right: list[bool]) -> np.ndarray:
        """(L, P) bool, per submap length and loop point, from the outcome of each of ``points``:
        the points between two registered ones take the last one's outcome."""
        every = max(1, int(round(self.params.every / loop.step)))
        placed = np.zeros((len(submap_lengths(self.params)), len(loop)), dtype=bool)
        for (level, at), ok in zip(points, right, strict=True):
            placed[level, at : at + every] = ok
        return placed

    def placed_along(self, loop: Loop) -> np.ndarray:
        """(L, P) bool, per submap length of :func:`submap_lengths` and loop point: True where the
        registration of that many metres of the loop before the point is unique and right."""
        points = self.points(loop)
        return self.placed_from(loop, points, self.placed_at(loop, points))


def lidar_distances(
    entries: list[Entry | None],
    placed: list[np.ndarray],
    loops: list[Loop],
    params: RegistrationParams,
    limit_m: float,
) -> np.ndarray:
    """(S,) m driven until the lidar places each start (``inf``: not within ``limit_m``): its
    approach, then along its loop from where it joins, to the first point placed by the longest
    submap of :func:`submap_lengths` it has driven (``placed``: per loop,
    :meth:`LoopRegistration.placed_along`)."""
    lengths = submap_lengths(params)
    out = np.full(len(entries), np.inf)
    for s, entry in enumerate(entries):
        if entry is None:
            continue
        loop, ok = loops[entry.loop], placed[entry.loop]
        n = len(loop)
        if not ok.any():
            continue
        last = int((limit_m - entry.length) / loop.step)
        for level, length in enumerate(lengths):
            # the steps along the loop at which this submap length is the longest one driven
            lo = max(0, int(math.ceil((length - entry.length) / loop.step)))
            hi = min(last, lo + n - 1)
            if level + 1 < len(lengths):  # until the next length is driven
                hi = min(hi, int(math.ceil((lengths[level + 1] - entry.length) / loop.step)) - 1)
            if hi < lo or not ok[level].any():
                continue
            ahead = np.roll(ok[level], -entry.index)  # ahead[k]: k steps on from where it joins
            hits = np.flatnonzero(ahead[np.arange(lo, hi + 1) % n])
            if len(hits):
                out[s] = entry.length + (lo + int(hits[0])) * loop.step
                break
    return out
