"""Verification of a match's hypotheses against the log: negative evidence and the lidar's fit.

:mod:`initcli.core.verification` holds the checks; this module gathers their inputs from a detection
log (its images' odom poses, every sighting, the scans) and a site storey (the BIM features, walls
and map). The online session and ``bim-init match`` both call :func:`verify_transform`, so a
session's verdict replays from its log.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bimtools.site.load import Site, StoreyModel
from initcli.core.classes import ClassMap
from initcli.core.detection_filter import Sighting
from initcli.core.geometry import Pose2D
from initcli.core.particle_filter import LikelihoodField
from initcli.core.verification import (
    CameraView,
    FreeSpace,
    ScanSample,
    Verification,
    VerificationParams,
    verify_hypothesis,
)
from initcli.io.detection_log import DetectionLog, Detections, Odom, Scan
from initcli.match.pipeline import MatchReport
from initcli.match.sightings import sightings_from_log

SCAN_BEAM_STEP = 3  # every third beam is enough for a fit share
RECENT_SCANS_M = 8.0  # m of the latest travel whose scans are fitted (older ones carry odometry drift)
MAX_SCANS = 16  # scans fitted at most, the latest first
PATH_WINDOW_M = 60.0  # m of the latest travel whose images predict features
PATH_CHECK_M = 30.0  # m of the latest travel that must lie in the BIM's free space


@dataclass
class StoreyEvidence:
    """A storey's BIM side of the checks, prepared once (the likelihood field is the costly part)."""

    ids: list[str]
    xy: np.ndarray
    normals: np.ndarray
    heights: np.ndarray
    categories: list[str]
    walls: np.ndarray
    field_: LikelihoodField | None
    free: FreeSpace | None = None

    @staticmethod
    def of(storey: StoreyModel, cmap: ClassMap) -> StoreyEvidence:
        f = storey.features
        walls = np.array([[w.x1, w.y1, w.x2, w.y2] for w in storey.walls], dtype=float).reshape(-1, 4)
        return StoreyEvidence(
            [x.id for x in f],
            np.array([[x.x, x.y] for x in f], dtype=float).reshape(-1, 2),
            np.array([[x.norm_x, x.norm_y] for x in f], dtype=float).reshape(-1, 2),
            np.array([x.height for x in f], dtype=float),
            [cmap.canonical(x.category) for x in f],
            walls,
            LikelihoodField(storey.grid) if storey.grid is not None else None,
            FreeSpace(storey.grid, VerificationParams().path_margin) if storey.grid is not None else None,
        )


@dataclass
class PathEvidence:
    """The robot's side: odom poses of the images, every sighting, and the recent scans."""

    image_poses: list[Pose2D] = field(default_factory=list)
    image_travel: list[float] = field(default_factory=list)  # odometry distance at each image, m
    scans: list[ScanSample] = field(default_factory=list)
    scan_travel: list[float] = field(default_factory=list)

    def recent(self, window_m: float, scan_window_m: float) -> tuple[list[Pose2D], list[ScanSample]]:
        now = max(
            self.image_travel[-1] if self.image_travel else 0.0,
            self.scan_travel[-1] if self.scan_travel else 0.0,
        )
        poses = [p for p, d in zip(self.image_poses, self.image_travel, strict=True) if now - d <= window_m]
        scans = [s for s, d in zip(self.scans, self.scan_travel, strict=True) if now - d <= scan_window_m]
        return poses, scans[-MAX_SCANS:]

    def add_image(self, odom: Pose2D, travel: float) -> None:
        self.image_poses.append(odom)
        self.image_travel.append(travel)

    def add_scan(
        self, odom: Pose2D, travel: float, angles: np.ndarray, ranges: np.ndarray, range_max: float
    ) -> None:
        self.scans.append(
            ScanSample(
                odom, np.asarray(angles)[::SCAN_BEAM_STEP], np.asarray(ranges)[::SCAN_BEAM_STEP], range_max
            )
        )
        self.scan_travel.append(travel)
        if len(self.scans) > 4 * MAX_SCANS:
            del self.scans[: -2 * MAX_SCANS]
            del self.scan_travel[: -2 * MAX_SCANS]

    @staticmethod
    def of_log(log: DetectionLog) -> PathEvidence:
        """The images' odom poses and the scans (at the latest odom pose before each) of a log."""
        out = PathEvidence()
        travel = 0.0
        last: Pose2D | None = None
        for rec in log.records:
            if isinstance(rec, Odom):
                here = Pose2D(rec.x, rec.y, rec.yaw)
                if last is not None:
                    travel += last.distance_to(here)
                last = here
            elif isinstance(rec, Scan) and last is not None:
                n = len(rec.ranges)
                angles = rec.angle_min + rec.angle_increment * np.arange(n)
                ranges = np.array([math.nan if r is None else r for r in rec.ranges], dtype=float)
                out.add_scan(last, travel, angles, ranges, rec.range_max)
            elif isinstance(rec, Detections):
                out.add_image(rec.pose, travel)
        return out


def verify_transform(
    transform: Pose2D,
    storey: StoreyEvidence,
    path: PathEvidence,
    sightings: Sequence[Sighting],
    view: CameraView,
    params: VerificationParams,
) -> Verification:
    """The checks of :func:`initcli.core.verification.verify_hypothesis` for ``transform`` (odom ->
    BIM) on ``storey``, with the images of the last ``PATH_WINDOW_M`` m and the scans of the last
    ``RECENT_SCANS_M`` m."""
    poses, scans = path.recent(PATH_WINDOW_M, RECENT_SCANS_M)
    recent_path, _ = path.recent(PATH_CHECK_M, 0.0)
    return verify_hypothesis(
        transform,
        storey.ids,
        storey.xy,
        storey.normals,
        storey.heights,
        storey.categories,
        poses,
        np.array([[s.x, s.y] for s in sightings], dtype=float).reshape(-1, 2),
        [s.cls for s in sightings],
        view,
        storey.walls,
        scans,
        storey.field_,
        params,
        storey.free,
        recent_path,
    )


def verify_report(
    log: DetectionLog,
    site: Site,
    report: MatchReport,
    cmap: ClassMap,
    params: VerificationParams | None = None,
) -> list[Verification | None]:
    """The checks for each hypothesis of ``report`` (a ``bim-init match`` of ``log``), at the log's
    last odom pose; None for a hypothesis whose storey has no map or features."""
    params = params or VerificationParams()
    if report.odom_pose is None:
        return [None for _ in report.hypotheses]
    path = PathEvidence.of_log(log)
    sightings = sightings_from_log(log, cmap, report.options.edge_margin)
    view = CameraView(log.meta.camera, log.meta.camera_pose, report.options.min_depth)
    storeys: dict[str, StoreyEvidence] = {}
    out: list[Verification | None] = []
    for h in report.hypotheses:
        model = site.storeys.get(h.storey)
        if model is None or not model.features:
            out.append(None)
            continue
        if h.storey not in storeys:
            storeys[h.storey] = StoreyEvidence.of(model, cmap)
        pose = h.reported_pose
        out.append(
            verify_transform(
                pose * report.odom_pose.inverse(), storeys[h.storey], path, sightings, view, params
            )
        )
    return out
