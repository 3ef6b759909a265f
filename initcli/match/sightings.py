"""Eq. 1-2 for the detection log's images: every detected box with a depth to a sighting in the odom frame.

``bim-init match`` converts a whole log at once (:func:`sightings_from_log`); the online session
converts each image as it arrives (:func:`image_sightings`). Both run the same code, so the
session's sightings are exactly those its log replays to.
"""

from __future__ import annotations

import math

import numpy as np

from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import Sighting, is_truncated
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, detections_to_odom
from initcli.io.detection_log import DetectionLog, Detections

__all__ = ["image_sightings", "sightings_from_log"]


def image_sightings(
    rec: Detections,
    frame: int,
    cmap: ClassMap,
    camera: CameraIntrinsics,
    mount: CameraMount,
    edge_margin: float,
) -> list[Sighting]:
    """Eq. 1-2 for the objects of one image (``frame``: its index among the log's images) that
    have a finite depth; a box within ``edge_margin`` px of the left or right border is truncated."""
    objs = [(o, o.depth) for o in rec.objects if o.depth is not None and math.isfinite(o.depth)]
    if not objs:
        return []
    pts = detections_to_odom(
        np.array([o.bbox for o, _ in objs]), np.array([d for _, d in objs]), camera, mount, rec.pose
    )  # Eq. 1-2
    return [
        Sighting(
            rec.t,
            cmap.canonical(o.cls),
            float(p[0]),
            float(p[1]),
            o.score,
            float(depth),
            frame,
            truncated=is_truncated(o.bbox, camera.width, edge_margin),
        )
        for (o, depth), p in zip(objs, pts, strict=True)
    ]


def sightings_from_log(log: DetectionLog, cmap: ClassMap, edge_margin: float) -> list[Sighting]:
    """Eq. 1-2 for every detected object of the log."""
    cam, mount = log.meta.camera, log.meta.camera_pose
    out: list[Sighting] = []
    for frame, rec in enumerate(log.detections):
        out.extend(image_sightings(rec, frame, cmap, cam, mount, edge_margin))
    return out
