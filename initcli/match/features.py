"""Steps 1-2 of the pipeline (paper §3.3.1): the log's sightings (Eq. 1-2) through the detection filter
into confirmed features (Eq. 3), the lidar landmarks joined in (:mod:`initcli.match.landmarks`), all
within the drift window when one is set; and the robot's odom pose now and its odom path.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from bimtools.site.load import Site
from bimtools.site.records import LIDAR
from initcli.config.matching import MatchOptions
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import (
    ConfirmedFeature,
    GivenFeature,
    Sighting,
    filter_detections,
    within_drift_window,
)
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import DetectionLog, FeatureRecord
from initcli.match.landmarks import combined_sequence, log_landmarks, recent_landmarks
from initcli.match.load import current_odom
from initcli.match.sightings import sightings_from_log

__all__ = ["confirmed_features"]


def confirmed_features(
    log: DetectionLog,
    site: Site,
    opts: MatchOptions,
    cmap: ClassMap,
    sightings: Sequence[Sighting] | None,
    warnings: list[str],
    notes: list[str],
) -> tuple[list[ConfirmedFeature], list[FeatureRecord] | None, Pose2D, np.ndarray]:
    """Steps 1-2: Eq. 1-2 and the detection filter, the lidar landmarks joined in
    (:mod:`initcli.match.landmarks`) and all within the drift window when one is set; every lidar
    landmark of the log (None: ``opts.landmarks`` off); the robot's odom pose now and its odom path."""
    if sightings is None:
        sightings = sightings_from_log(log, cmap, opts.edge_margin)
    given = [GivenFeature(f.t, cmap.canonical(f.cls), f.x, f.y) for f in log.features if f.source != LIDAR]
    filtered = filter_detections(sightings, opts.filter_params(), given)
    lidar: list[FeatureRecord] = []
    found: list[FeatureRecord] | None = None
    if opts.landmarks:
        found = log_landmarks(log, site, notes)
        lidar = recent_landmarks(found, log.odom, opts.landmark_window, site, cmap)
        if len(lidar) < len(found):
            notes.append(
                f"matched {len(lidar)} of {len(found)} lidar landmark(s): of a category the site has, "
                f"confirmed in the last {opts.landmark_window:g} m of travel"
            )
    features = combined_sequence(filtered.features, lidar, cmap)
    odom_pose, odom_path, more = current_odom(log)
    warnings.extend(more)
    if opts.drift_window is not None and log.odom and len(features) > opts.min_inliers:
        odom_t = np.array([o.t for o in log.odom])
        recent = within_drift_window(features, odom_t, odom_path[:, :2], opts.drift_window, opts.min_inliers)
        if len(recent) < len(features):
            notes.append(
                f"matched the {len(recent)} features confirmed in the last {opts.drift_window:g} m of "
                f"travel; {len(features) - len(recent)} older one(s) left out (odometry drift)"
            )
            features = recent
    return features, found, odom_pose, odom_path
