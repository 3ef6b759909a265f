"""The lidar landmarks of a detection log, and the mixed sequence S of camera features and landmarks.

A log's landmarks are its ``feature`` records with ``source: lidar`` (the online session writes each
one when its track is confirmed); a log with scans but no such records (a bag, a log written before
landmarks were on) has them found in its scans by the same tracker the session runs
(:class:`initcli.core.lidar.landmark_tracks.LandmarkTracker`, the scans in log order, each at the odom pose
of the latest odom record), so a session's log replays to the same landmarks either way. The rules
are the site's (site.json records the ``landmarks:`` block bim-extract applied); a site without
landmark rows has no landmarks matched, and a log's lidar records are then left out with a note.

The camera's features come from the detection filter (§3.3.1); the landmarks join them in order of
confirmation (the camera's first at equal times), numbered again as one S for Algorithm 1, with
the odometry travel at each confirmation (the landmarks' drift allowance).
"""

from __future__ import annotations

import bisect
from collections.abc import Iterator, Sequence

import numpy as np

from bimtools.site.load import Site
from bimtools.site.records import LIDAR
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.lidar.landmark_tracks import LandmarkTracker, ScanInput
from initcli.core.lidar.scan_landmarks import ScanLandmarkParams
from initcli.io.detection_log import DetectionLog, FeatureRecord, Odom, Scan

__all__ = [
    "combined_sequence",
    "feature_records",
    "log_landmarks",
    "recent_landmarks",
    "scan_inputs",
    "site_scan_params",
    "site_tracker",
    "travel_at",
]


def site_scan_params(site: Site) -> ScanLandmarkParams | None:
    """The scan rules of the site's landmarks (None: the site has no landmark rows or no rules)."""
    rules = site.manifest.landmarks if site.manifest is not None else None
    if rules is None or not rules.enabled or not any(s.lidar_landmarks for s in site.storeys.values()):
        return None
    return ScanLandmarkParams.from_rules(rules)


def site_tracker(site: Site) -> LandmarkTracker | None:
    """A landmark tracker with the site's rules (None: the site has no landmarks)."""
    params = site_scan_params(site)
    return LandmarkTracker(params) if params is not None else None


def scan_inputs(log: DetectionLog) -> Iterator[ScanInput]:
    """The log's scans in order, each at the odom pose of the latest odom record (the first before any)."""
    odom: list[Odom] = log.odom
    if not odom:
        return
    times = [o.t for o in odom]
    for scan in log.of_type(Scan):
        i = max(bisect.bisect_right(times, scan.t) - 1, 0)
        yield ScanInput(
            scan.t,
            odom[i].pose,
            np.asarray(scan.ranges, dtype=float),
            scan.angle_min,
            scan.angle_increment,
            scan.range_max,
        )


def log_landmarks(log: DetectionLog, site: Site, notes: list[str]) -> list[FeatureRecord]:
    """The log's lidar landmarks: its lidar ``feature`` records, else those found in its scans."""
    records = [f for f in log.features if f.source == LIDAR]
    if site_scan_params(site) is None:
        if records:
            notes.append(f"{len(records)} lidar landmark(s) of the log left out: the site has no landmarks")
        return []
    if not records:
        tracker = site_tracker(site)
        assert tracker is not None
        records = feature_records([f for scan in scan_inputs(log) for f in tracker.add_scan(scan)])
        if records:
            notes.append(f"{len(records)} lidar landmark(s) found in the log's {tracker.frames} scans")
    return records


def recent_landmarks(
    records: Sequence[FeatureRecord], odom: Sequence[Odom], window: float, site: Site, cmap: ClassMap
) -> list[FeatureRecord]:
    """The landmarks worth matching: of a category the site has (no other can be matched), confirmed
    within the last ``window`` m of odometry travel (0: all)."""
    known = {cmap.canonical(f.category) for s in site.storeys.values() for f in s.lidar_landmarks}
    kept = [r for r in records if cmap.canonical(r.cls) in known]
    if window <= 0 or not kept or not odom:
        return kept
    travel = travel_at(odom, [r.t for r in kept])
    now = float(travel_at(odom, [odom[-1].t])[0])
    return [r for r, d in zip(kept, travel, strict=True) if d >= now - window]


def feature_records(found: Sequence[ConfirmedFeature]) -> list[FeatureRecord]:
    """Landmarks confirmed by the tracker as the log's ``feature`` records (``source: lidar``)."""
    return [FeatureRecord(f.t_confirmed, f.cls, f.x, f.y, LIDAR) for f in found]


def combined_sequence(
    camera: Sequence[ConfirmedFeature], lidar: Sequence[FeatureRecord], cmap: ClassMap
) -> list[ConfirmedFeature]:
    """S: the camera's confirmed features and the lidar landmarks in order of confirmation."""
    if not lidar:
        return list(camera)
    k = max((f.sightings for f in camera), default=1)
    events = [(f.t_confirmed, 0, i, f) for i, f in enumerate(camera)]
    events += [
        (r.t, 1, i, ConfirmedFeature(0, cmap.canonical(r.cls), r.x, r.y, k, r.t, r.t, given=True))
        for i, r in enumerate(lidar)
    ]
    events.sort(key=lambda e: (e[0], e[1], e[2]))
    return [
        ConfirmedFeature(n, f.cls, f.x, f.y, f.sightings, f.t_first, f.t_confirmed, f.given)
        for n, (_t, _kind, _i, f) in enumerate(events)
    ]


def travel_at(odom: Sequence[Odom], times: Sequence[float]) -> np.ndarray:
    """m of odometry travel up to each time (the latest odom record at or before it)."""
    if not odom:
        return np.zeros(len(times))
    xy = np.array([[o.x, o.y] for o in odom])
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    idx = np.searchsorted(np.array([o.t for o in odom]), np.asarray(times, dtype=float), side="right") - 1
    return np.asarray(cum[np.clip(idx, 0, len(cum) - 1)], dtype=float)
