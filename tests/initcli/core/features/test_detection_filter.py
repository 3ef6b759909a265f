"""The detection filter: sightings -> confirmed features S_object (Eq. 3)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from initcli.core.features.detection_filter import (
    ConfirmedFeature,
    DetectionFilter,
    GivenFeature,
    Sighting,
    filter_detections,
    within_drift_window,
)
from initcli.match.pipeline import MatchOptions

DEFAULTS = MatchOptions().filter_params()  # the tool's detection-filter settings


def s(
    t: float,
    x: float,
    y: float = 0.0,
    cls: str = "door",
    score: float = 0.9,
    depth: float = 3.0,
    frame: int = -1,
):
    return Sighting(t, cls, x, y, score, depth, frame if frame >= 0 else int(t * 10))


def test_k_sightings_confirm_at_the_kth() -> None:
    two = filter_detections([s(0.0, 1.0), s(0.2, 1.1)], DEFAULTS)
    assert two.features == [] and two.unconfirmed_tracks == 1
    three = filter_detections([s(0.0, 1.0), s(0.2, 1.1), s(0.4, 0.9)], DEFAULTS)
    (f,) = three.features
    assert f.sightings == 3 and f.t_confirmed == 0.4 and f.t_first == 0.0
    assert (f.x, f.y) == (1.0, 0.0)


def test_score_and_depth_thresholds() -> None:
    out = filter_detections(
        [s(0.0, 1.0, score=0.4), s(0.1, 1.0), s(0.2, 1.0, depth=12.0), s(0.3, 1.0, depth=0.0), s(0.4, 1.0)],
        replace(DEFAULTS, min_sightings=2),
    )
    assert out.rejected_score == 1 and out.rejected_depth == 2 and out.used == 2
    assert len(out.features) == 1


def test_classes_and_radius_separate_features_and_order_is_confirmation_time() -> None:
    sightings = [
        s(0.0, 0.0),
        s(0.1, 5.0, cls="lift"),
        s(0.2, 0.3, cls="lift"),  # a lift 0.3 m from a door: separate
        s(0.3, 5.1, cls="lift"),
        s(0.4, 4.9, cls="lift"),  # lift at 5 confirmed at 0.4
        s(0.5, 0.1),
        s(0.6, 2.5),
        s(0.7, -0.1),  # door at 0 confirmed at 0.7; door at 2.5 seen once
        s(0.8, 0.35, cls="lift"),
        s(0.9, 0.25, cls="lift"),  # lift at 0.3 confirmed at 0.9
    ]
    out = filter_detections(sightings, DEFAULTS)
    assert [(f.cls, round(f.x, 1)) for f in out.features] == [("lift", 5.0), ("door", 0.0), ("lift", 0.3)]
    assert [f.index for f in out.features] == [0, 1, 2]
    assert out.unconfirmed_tracks == 1


def test_one_sighting_per_image_per_feature() -> None:
    # two boxes on the same door in each of two images: 2 sightings, not 4
    same = [s(0.0, 1.0, frame=1), s(0.0, 1.2, frame=1), s(0.2, 1.0, frame=2), s(0.2, 1.1, frame=2)]
    out = filter_detections(same, replace(DEFAULTS, min_sightings=3, merge_radius=0.1))
    assert out.features == []
    out = filter_detections(same, replace(DEFAULTS, min_sightings=2, merge_radius=0.5))
    assert [f.sightings for f in out.features] == [2]


def test_duplicates_are_suppressed_when_tracks_drift_together() -> None:
    # two tracks 1.2 m apart (radius 1.0); sightings in between pull them together -> merged, older kept
    seq = [
        s(0.0, 0.0),
        s(0.1, 1.2),
        s(0.2, 0.0),
        s(0.3, 1.2),
        s(0.4, 0.0),
        s(0.5, 0.7),
        s(0.6, 0.6),
        s(0.7, 0.5),
    ]
    out = filter_detections(seq, DEFAULTS)
    assert len(out.features) == 1
    assert out.features[0].sightings == len(seq)
    assert out.features[0].t_confirmed == 0.4


def test_given_features_are_confirmed_and_fixed() -> None:
    out = filter_detections(
        [s(1.0, 3.3), s(1.2, 3.4), s(2.0, 7.0), s(2.2, 7.0), s(2.4, 7.0)],
        DEFAULTS,
        given=[GivenFeature(0.5, "door", 3.0, 0.0)],
    )
    assert [(f.x, f.given) for f in out.features] == [(3.0, True), (7.0, False)]
    assert out.features[0].sightings == 5  # k for the record + 2 sightings


def test_class_confusion_does_not_create_a_feature():
    """Rule 6: a door seen 20 times and called a lift 3 times is one door."""
    from initcli.core.features.detection_filter import Sighting, filter_detections

    sightings = [Sighting(t=0.1 * i, cls="door", x=2.0, y=1.0, frame=i) for i in range(20)]
    sightings += [Sighting(t=0.1 * i + 0.05, cls="lift", x=2.1, y=1.0, frame=100 + i) for i in range(3)]
    features = filter_detections(sightings, DEFAULTS).features
    assert [f.cls for f in features] == ["door"]
    # A real lift next to the door, seen about as often, is kept.
    sightings += [Sighting(t=5 + 0.1 * i, cls="lift", x=2.5, y=1.0, frame=200 + i) for i in range(10)]
    assert sorted(f.cls for f in filter_detections(sightings, DEFAULTS).features) == ["door", "lift"]
    no_rule6 = replace(DEFAULTS, class_dominance=0)
    assert [f.cls for f in filter_detections(sightings[:23], no_rule6).features] == [
        "door",
        "lift",
    ]


def feature(i: int, t: float) -> ConfirmedFeature:
    return ConfirmedFeature(i, "door", float(i), 0.0, 5, t - 1.0, t)


def test_drift_window_keeps_the_features_of_the_last_metres():
    odom_t = np.arange(0.0, 101.0)  # 1 m/s along x for 100 s
    odom_xy = np.column_stack([odom_t, np.zeros_like(odom_t)])
    features = [feature(i, t) for i, t in enumerate([5.0, 20.0, 55.0, 70.0, 90.0, 99.0])]
    recent = within_drift_window(features, odom_t, odom_xy, 50.0)
    assert [f.index for f in recent] == [2, 3, 4, 5]
    # never fewer than keep_at_least (the newest)
    assert [f.index for f in within_drift_window(features, odom_t, odom_xy, 5.0, 3)] == [3, 4, 5]
    # standing still: nothing is old
    still = np.zeros((101, 2))
    assert len(within_drift_window(features, odom_t, still, 1.0)) == 6


def test_online_filter_equals_the_batch_filter_after_every_image():
    """A session feeds each image's sightings as they come: after each, the same S_object (positions,
    counts, confirmation times, merges, rule 6) as filtering everything from the start."""
    rng = np.random.default_rng(3)
    doors = rng.uniform(0, 20, size=(8, 2))
    sightings = []
    for frame in range(300):
        t = 0.2 * frame
        for i in rng.choice(len(doors), size=int(rng.integers(0, 4)), replace=False):
            cls = "lift" if rng.random() < 0.1 else "door"  # class confusion now and then
            x, y = doors[i] + rng.normal(0, 0.25, 2)
            depth = float(rng.choice([3.0, 3.0, 3.0, 12.0]))  # some out of range
            sightings.append(Sighting(t, cls, float(x), float(y), float(rng.uniform(0.3, 1)), depth, frame))
    online = DetectionFilter(DEFAULTS)
    fed = 0
    checked = 0
    for end in range(1, len(sightings) + 1):
        if end < len(sightings) and sightings[end].frame == sightings[end - 1].frame:
            continue  # compare at the end of each image
        for sighting in sightings[fed:end]:
            online.add(sighting)
        fed = end
        assert online.result() == filter_detections(sightings[:end], DEFAULTS)
        checked += 1
    assert checked > 100 and len(online.result().features) >= 5


def test_online_filter_refuses_events_out_of_time_order():
    online = DetectionFilter(DEFAULTS)
    online.add(s(1.0, 0.0))
    with pytest.raises(ValueError, match="time order"):
        online.add(s(0.5, 0.0))
