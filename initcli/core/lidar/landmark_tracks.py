"""Lidar landmarks along a path: each scan's corners and openings (:mod:`initcli.core.lidar.scan_landmarks`)
placed in the odom frame by the odometry pose of the scan, then merged and confirmed like camera
sightings (§3.3.1: :class:`initcli.core.features.detection_filter.DetectionFilter`, whose rules 2-4 and 6
apply unchanged: one sighting per scan per track, k sightings confirm, same-class tracks that drift
together merge, a track dominated by a nearby track of another class is a misreading of it).

A landmark l seen at p_s (sensor frame) from odom pose x_t = (x, y, yaw) with the lidar mounted at
m on the base lies at ``p_o = R(yaw) (R(m_yaw) p_s + m_xy) + (x, y)`` (Eq. 11's transform twice);
its covariance turns with it, ``C_o = R C_s R^T`` (R the whole rotation). A confirmed landmark's
position is the mean of its n sightings (the filter's), its covariance the mean's,
``sum C_o,i / n^2`` (sightings taken as independent: odometry between scans of one pass is far
more precise than a scan), its normal the normalised sum of the sightings' normals. Pure numpy.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from initcli.core.features.detection_filter import ConfirmedFeature, DetectionFilter, FilterParams, Sighting
from initcli.core.geometry.se2 import Pose2D, rot2
from initcli.core.lidar.scan_landmarks import ScanLandmark, ScanLandmarkParams, scan_landmarks


@dataclass(frozen=True)
class TrackParams:
    """How scan landmarks become confirmed landmarks."""

    # m: same-class sightings closer than this are one landmark; below half of min_leg (0.3 m), so
    # the two corners of the shortest face a corner may have stay two
    merge_radius: float = 0.15
    min_sightings: int = 3  # k: scans a landmark must be seen in
    max_range: float = 8.0  # m: landmarks farther from the lidar are not used (beams 14 cm apart at 1 deg)
    class_dominance: float = 4.0  # as the camera filter's rule 6

    def filter_params(self) -> FilterParams:
        """The detection filter's settings for lidar sightings: no score, depth = range, no image border."""
        return FilterParams(
            merge_radius=self.merge_radius,
            min_sightings=self.min_sightings,
            score_threshold=-math.inf,
            min_depth=0.0,
            max_depth=self.max_range,
            edge_margin=-1.0,
            class_dominance=self.class_dominance,
        )


@dataclass(frozen=True)
class LandmarkSighting:
    """One scan landmark in the odom frame."""

    t: float
    frame: int  # the scan's index
    category: str
    x: float
    y: float
    normal: tuple[float, float]
    cov: np.ndarray  # (2, 2) m^2
    range: float  # m from the lidar


@dataclass(frozen=True)
class LidarLandmark:
    """A confirmed lidar landmark in the odom frame (a row of S for the lidar)."""

    index: int  # confirmation order
    category: str
    x: float
    y: float
    normal: tuple[float, float]
    cov: np.ndarray  # (2, 2) m^2: of the mean position
    sightings: int
    t_first: float
    t_confirmed: float

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])

    @property
    def sigma(self) -> float:
        """m: the larger standard deviation of the position."""
        return float(math.sqrt(max(np.linalg.eigvalsh(self.cov).max(), 0.0)))


@dataclass(frozen=True)
class ScanInput:
    """One scan and the odometry pose it was taken at."""

    t: float
    pose: Pose2D  # odom frame
    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_max: float


def to_odom(
    t: float, frame: int, pose: Pose2D, found: Sequence[ScanLandmark], mount: Pose2D | None = None
) -> list[LandmarkSighting]:
    """Scan landmarks (sensor frame) -> sightings in the odom frame (the module doc's transform)."""
    base = pose if mount is None else pose.compose(mount)
    r = rot2(base.yaw)
    out: list[LandmarkSighting] = []
    for lm in found:
        p = r @ lm.xy + np.array([base.x, base.y])
        n = r @ np.asarray(lm.normal)
        out.append(
            LandmarkSighting(
                t,
                frame,
                lm.category,
                float(p[0]),
                float(p[1]),
                (float(n[0]), float(n[1])),
                r @ lm.cov @ r.T,
                lm.range,
            )
        )
    return out


def merge_sightings(sightings: Iterable[LandmarkSighting], params: TrackParams) -> list[LidarLandmark]:
    """Sightings in time order -> confirmed landmarks, ordered by confirmation (the detection filter)."""
    sightings = list(sightings)
    online = DetectionFilter(params.filter_params())
    for s in sightings:
        online.add(Sighting(s.t, s.category, s.x, s.y, score=1.0, depth=s.range, frame=s.frame))
    confirmed = online.result().features
    used = [s for s in sightings if s.range <= params.max_range]
    members: list[list[LandmarkSighting]] = [[] for _ in confirmed]
    for s in used:
        best, best_d = -1, params.merge_radius
        for i, f in enumerate(confirmed):
            d = math.hypot(f.x - s.x, f.y - s.y)
            if f.cls == s.category and d <= best_d:
                best, best_d = i, d
        if best >= 0:
            members[best].append(s)
    out: list[LidarLandmark] = []
    for f, group in zip(confirmed, members, strict=True):
        if not group:
            continue
        normal = np.sum([s.normal for s in group], axis=0)
        normal = normal / max(float(np.hypot(*normal)), 1e-12)
        cov = np.sum([s.cov for s in group], axis=0) / len(group) ** 2
        out.append(
            LidarLandmark(
                f.index,
                f.cls,
                f.x,
                f.y,
                (float(normal[0]), float(normal[1])),
                cov,
                f.sightings,
                f.t_first,
                f.t_confirmed,
            )
        )
    return out


class LandmarkTracker:
    """The landmarks of a path one scan at a time, each confirmed landmark given once, when it is
    confirmed, where its track is then (the online session writes it to its log at that moment, and
    ``bim-init match`` replays a log's scans through the same tracker: the same landmarks)."""

    def __init__(
        self, params: ScanLandmarkParams, track: TrackParams | None = None, mount: Pose2D | None = None
    ):
        self.params = params
        self.track = track or TrackParams()
        self.mount = mount
        self.filter = DetectionFilter(self.track.filter_params())
        self.frames = 0  # scans added so far
        self._seen: set[int] = set()

    def add_scan(self, scan: ScanInput) -> list[ConfirmedFeature]:
        """One scan's landmarks into the tracks; the landmarks it confirmed (odom frame)."""
        p = self.params
        found = scan_landmarks(scan.ranges, scan.angle_min, scan.angle_increment, scan.range_max, p)
        for s in to_odom(scan.t, self.frames, scan.pose, found, self.mount):
            self.filter.add(Sighting(s.t, s.category, s.x, s.y, score=1.0, depth=s.range, frame=s.frame))
        self.frames += 1
        return self.filter.confirmed_new(self._seen)


def accumulate_landmarks(
    scans: Iterable[ScanInput],
    params: ScanLandmarkParams,
    track: TrackParams | None = None,
    mount: Pose2D | None = None,
) -> list[LidarLandmark]:
    """The confirmed lidar landmarks of a path: every scan's landmarks, in the odom frame, merged."""
    track = track or TrackParams()
    sightings: list[LandmarkSighting] = []
    for frame, scan in enumerate(scans):
        found = scan_landmarks(scan.ranges, scan.angle_min, scan.angle_increment, scan.range_max, params)
        sightings += to_odom(scan.t, frame, scan.pose, found, mount)
    return merge_sightings(sightings, track)


__all__ = [
    "LandmarkSighting",
    "LandmarkTracker",
    "LidarLandmark",
    "ScanInput",
    "TrackParams",
    "accumulate_landmarks",
    "merge_sightings",
    "to_odom",
]
