"""Detection filter (§3.3.1, §3.3.4): raw per-image sightings -> confirmed features S_object (Eq. 3).

Rules, applied to the sightings in time order:

1. A sighting is used only if its score is >= ``score_threshold``, its depth lies in
   ``[min_depth, max_depth]`` (depth noise grows with range; zero/invalid depth is dropped) and
   its box does not touch or cross the left/right image border (within ``edge_margin`` px): a
   box cut by the border has its centre off the object's centre, which biases Eq. 1 sideways.
2. It joins the nearest *track* of the same class whose mean position is within
   ``merge_radius``; otherwise it starts a new track. One image adds at most one sighting to a
   track (two boxes on one door in the same image count once).
3. A track is *confirmed* when it has ``min_sightings`` sightings (k), at the time of that
   sighting. S_object is ordered by confirmation time (Eq. 3), ties by creation order.
4. Duplicate suppression: when two same-class tracks drift to within ``merge_radius`` of each
   other they are merged into the older one (sightings summed; the earlier confirmation kept).
5. ``feature`` records of the log (a robot that aggregates itself) are confirmed at their time
   with their given position, which later sightings do not move.
6. Class confusion: a track is not confirmed while a track of another class within
   ``merge_radius`` has ``class_dominance`` times its sightings (a door seen 40 times and called a
   lift twice is one door), and a confirmed track that ends up so dominated is dropped.

Positions are the mean of the sightings' odom positions (Eq. 1-2 results).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "ConfirmedFeature",
    "DetectionFilter",
    "FilterParams",
    "FilterResult",
    "GivenFeature",
    "Sighting",
    "filter_detections",
    "is_truncated",
    "within_drift_window",
]


@dataclass(frozen=True)
class FilterParams:
    """Settings of the detection filter (their one default: ``initcli.match.pipeline.MatchOptions``)."""

    merge_radius: float  # m: same-class sightings closer than this are the same feature
    min_sightings: int  # k: sightings needed to confirm a feature
    score_threshold: float  # detector score below this is ignored
    min_depth: float  # m: depth window readings outside [min, max] are ignored
    max_depth: float  # m
    edge_margin: float  # px: boxes this close to the left/right border are truncated; < 0 keeps them
    # A track with a track of another class within merge_radius that has this many times its
    # sightings is a misclassification of that object (rule 6), not a feature of its own.
    class_dominance: float = 4.0


@dataclass(frozen=True)
class Sighting:
    """One detected object localised in the odom frame by Eq. 1-2."""

    t: float
    cls: str
    x: float
    y: float
    score: float = 1.0
    depth: float = 1.0
    frame: int = -1  # index of the image (detections record); -1: unknown
    truncated: bool = False  # the box touches the left/right image border (see is_truncated)


@dataclass(frozen=True)
class GivenFeature:
    """An already aggregated feature (log record ``feature``)."""

    t: float
    cls: str
    x: float
    y: float


@dataclass(frozen=True)
class ConfirmedFeature:
    """A confirmed detected feature s_i of S_object (Eq. 3), in the odom frame."""

    index: int  # position in S_object (0-based)
    cls: str
    x: float
    y: float
    sightings: int
    t_first: float
    t_confirmed: float
    given: bool = False  # True if it came from a ``feature`` record

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])


@dataclass
class _Track:
    cls: str
    sum_x: float
    sum_y: float
    n: int
    t_first: float
    created: int
    last_frame: int
    confirmed_at: float | None = None
    fixed: tuple[float, float] | None = None
    frames: set[int] = field(default_factory=set)
    n_pos: int = 1  # positions summed in sum_x, sum_y (n counts sightings: one per image)

    @property
    def pos(self) -> tuple[float, float]:
        if self.fixed is not None:
            return self.fixed
        return self.sum_x / self.n_pos, self.sum_y / self.n_pos


@dataclass
class FilterResult:
    features: list[ConfirmedFeature]
    used: int = 0
    rejected_score: int = 0
    rejected_depth: int = 0
    rejected_truncated: int = 0
    unconfirmed_tracks: int = 0


def is_truncated(bbox: Sequence[float], image_width: float, margin: float) -> bool:
    """Does the box ``[u1, v1, u2, v2]`` touch or cross the left or right image border?"""
    return bool(margin >= 0 and (bbox[0] <= margin or bbox[2] >= image_width - margin))


def filter_detections(
    sightings: Iterable[Sighting],
    params: FilterParams,
    given: Sequence[GivenFeature] = (),
) -> FilterResult:
    """Aggregate sightings (and given features) into S_object, ordered by confirmation time."""
    # Given features before sightings at the same time, each in input order.
    events: list[tuple[float, int, int, GivenFeature | Sighting]] = []
    for order, sighting in enumerate(sightings):
        events.append((sighting.t, 1, order, sighting))
    for order, feature in enumerate(given):
        events.append((feature.t, 0, order, feature))
    events.sort(key=lambda e: (e[0], e[1], e[2]))
    online = DetectionFilter(params)
    for _t, _kind, _order, item in events:
        if isinstance(item, GivenFeature):
            online.add_given(item)
        else:
            online.add(item)
    return online.result()


class DetectionFilter:
    """The rules above applied online, one event at a time in time order (a session feeds each
    image's sightings as they come): the same tracks and S_object as :func:`filter_detections` on
    all of them, at the cost of the new sightings only."""

    def __init__(self, params: FilterParams) -> None:
        self.params = params
        self.k = max(1, int(params.min_sightings))
        self.tracks: list[_Track] = []
        self.created = 0
        self.t = -math.inf  # s: the last event's time
        self.counts = FilterResult(features=[])  # the rejection counters

    def _advance(self, t: float) -> None:
        if t < self.t:
            raise ValueError(f"detection filter: event at t={t} after one at t={self.t} (feed in time order)")
        self.t = t

    def add_given(self, g: GivenFeature) -> None:
        """Rule 5: a feature aggregated by the robot, fixed where it is given."""
        self._advance(g.t)
        k = self.k
        track = _nearest(self.tracks, g.cls, g.x, g.y, self.params.merge_radius, frame=None)
        if track is None:
            self.tracks.append(
                _Track(g.cls, g.x, g.y, k, g.t, self.created, -1, confirmed_at=g.t, fixed=(g.x, g.y))
            )
            self.created += 1
        else:
            track.fixed = (g.x, g.y)
            track.n = max(track.n, k)
            if track.confirmed_at is None:
                track.confirmed_at = g.t

    def add(self, s: Sighting) -> None:
        """Rules 1-4 and 6 for one sighting."""
        self._advance(s.t)
        p, counts, tracks = self.params, self.counts, self.tracks
        if not (s.score >= p.score_threshold):
            counts.rejected_score += 1
            return
        if not (math.isfinite(s.depth) and p.min_depth <= s.depth <= p.max_depth):
            counts.rejected_depth += 1
            return
        if s.truncated and p.edge_margin >= 0:
            counts.rejected_truncated += 1
            return
        counts.used += 1
        track = _nearest(tracks, s.cls, s.x, s.y, p.merge_radius, frame=s.frame)
        if track is None:
            track = _Track(s.cls, s.x, s.y, 1, s.t, self.created, s.frame, frames={s.frame})
            self.created += 1
            tracks.append(track)
        else:
            track.sum_x += s.x
            track.sum_y += s.y
            track.n_pos += 1
            track.n += 1
            track.last_frame = s.frame
            track.frames.add(s.frame)
        if track.confirmed_at is None and track.n >= self.k and not _misclassified(tracks, track, p):
            track.confirmed_at = s.t
        _suppress_duplicates(tracks, track, p.merge_radius, s.t, self.k)

    def confirmed_new(self, seen: set[int]) -> list[ConfirmedFeature]:
        """The features confirmed since the last call (``seen``: the track numbers returned before,
        updated here) that rule 6 keeps now, in confirmation order, each where its track is now: for a
        caller that writes every feature once, when it is confirmed (the session's lidar landmarks).
        ``index`` is the track's number."""
        fresh = [
            tr
            for tr in self.tracks
            if tr.confirmed_at is not None
            and tr.created not in seen
            and (tr.fixed is not None or not _misclassified(self.tracks, tr, self.params))
        ]
        fresh.sort(key=lambda tr: (tr.confirmed_at, tr.created))
        seen.update(tr.created for tr in fresh)
        return [
            ConfirmedFeature(
                index=tr.created,
                cls=tr.cls,
                x=float(tr.pos[0]),
                y=float(tr.pos[1]),
                sightings=int(tr.n),
                t_first=float(tr.t_first),
                t_confirmed=float(tr.confirmed_at),  # type: ignore[arg-type]
                given=tr.fixed is not None,
            )
            for tr in fresh
        ]

    def result(self) -> FilterResult:
        """S_object so far (Eq. 3), ordered by confirmation time, with the counters."""
        tracks, p = self.tracks, self.params
        confirmed = [
            (tr.confirmed_at, tr)
            for tr in tracks
            if tr.confirmed_at is not None and (tr.fixed is not None or not _misclassified(tracks, tr, p))
        ]
        confirmed.sort(key=lambda c: (c[0], c[1].created))
        result = dataclasses.replace(self.counts, features=[])
        result.unconfirmed_tracks = len(tracks) - len(confirmed)
        for i, (t_confirmed, tr) in enumerate(confirmed):
            x, y = tr.pos
            result.features.append(
                ConfirmedFeature(
                    index=i,
                    cls=tr.cls,
                    x=float(x),
                    y=float(y),
                    sightings=int(tr.n),
                    t_first=float(tr.t_first),
                    t_confirmed=float(t_confirmed),
                    given=tr.fixed is not None,
                )
            )
        return result


def _misclassified(tracks: list[_Track], track: _Track, p: FilterParams) -> bool:
    """Rule 6: is ``track`` dominated by a nearby track of another class (detector class confusion)?"""
    if p.class_dominance <= 0:
        return False
    x, y = track.pos
    for other in tracks:
        if other is track or other.cls == track.cls:
            continue
        ox, oy = other.pos
        if math.hypot(ox - x, oy - y) <= p.merge_radius and other.n >= p.class_dominance * track.n:
            return True
    return False


def _nearest(
    tracks: list[_Track], cls: str, x: float, y: float, radius: float, frame: int | None
) -> _Track | None:
    best: _Track | None = None
    best_d = radius
    for tr in tracks:
        if tr.cls != cls:
            continue
        if frame is not None and frame >= 0 and frame in tr.frames:
            continue  # one sighting per image per track
        tx, ty = tr.pos
        d = math.hypot(tx - x, ty - y)
        if d <= best_d:
            best, best_d = tr, d
    return best


def _suppress_duplicates(tracks: list[_Track], moved: _Track, radius: float, t: float, k: int) -> None:
    """Merge same-class tracks that came within ``radius`` of ``moved`` into the older one."""
    while True:
        mx, my = moved.pos
        other = None
        for tr in tracks:
            if tr is moved or tr.cls != moved.cls:
                continue
            tx, ty = tr.pos
            if math.hypot(tx - mx, ty - my) <= radius:
                other = tr
                break
        if other is None:
            return
        keep, drop = (moved, other) if moved.created < other.created else (other, moved)
        keep.sum_x += drop.sum_x
        keep.sum_y += drop.sum_y
        keep.n_pos += drop.n_pos
        shared = len((keep.frames & drop.frames) - {-1})  # one sighting per image, also after a merge
        keep.n += drop.n - shared
        keep.frames |= drop.frames
        keep.t_first = min(keep.t_first, drop.t_first)
        if keep.fixed is None:
            keep.fixed = drop.fixed
        times = [c for c in (keep.confirmed_at, drop.confirmed_at) if c is not None]
        keep.confirmed_at = min(times) if times else (t if keep.n >= k else None)
        tracks.remove(drop)
        moved = keep


def within_drift_window(
    features: list[ConfirmedFeature],
    odom_t: np.ndarray,
    odom_xy: np.ndarray,
    window_m: float,
    keep_at_least: int = 3,
) -> list[ConfirmedFeature]:
    """The features confirmed within the last ``window_m`` metres of travel.

    Odometry drifts with distance (the motion model's alpha2/alpha3 terms), so after a long
    exploration the relative positions of S_object's oldest and newest features no longer agree
    with the BIM within alpha (Eq. 7) and no hypothesis survives; the recent part still does.
    At least ``keep_at_least`` (the newest) are kept.
    """
    if not features or len(odom_t) == 0:
        return list(features)
    steps = np.hypot(*np.diff(odom_xy, axis=0).T) if len(odom_xy) > 1 else np.zeros(0)
    travelled = np.concatenate([[0.0], np.cumsum(steps)])
    now = travelled[-1]
    at = travelled[np.clip(np.searchsorted(odom_t, [f.t_confirmed for f in features]), 0, len(odom_t) - 1)]
    recent = [f for f, d in zip(features, at, strict=True) if now - d <= window_m]
    if len(recent) < keep_at_least:
        return list(features[-keep_at_least:])
    return recent
