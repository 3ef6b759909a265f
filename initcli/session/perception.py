"""What the session sees and writes down: its detection log, the sightings of each image
(Eq. 1-2), the confirmed features (Eq. 3), and the match step (Algorithm 1) on the log so far.

Every record the session acts on goes to its detection log as it happens (through
:class:`initcli.io.log_writer.LogWriter`), and the match step runs the same pipeline as
``bim-init match`` on that log, so the log replays to the same verdict and pose.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from bimtools.site.load import Site
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import ConfirmedFeature, DetectionFilter, Sighting
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.landmark_tracks import LandmarkTracker, ScanInput
from initcli.drivers.base import SensorFrame
from initcli.io.detection_log import (
    DetectionLog,
    Detections,
    FeatureRecord,
    HypothesesRecord,
    Meta,
    Odom,
    Record,
    Scan,
    Truth,
)
from initcli.io.log_writer import LogWriter
from initcli.match.landmarks import feature_records
from initcli.match.pipeline import Hypothesis, MatchOptions, MatchReport, match_log
from initcli.match.sightings import image_sightings
from initcli.verify.evidence import PathEvidence

__all__ = ["HYPOTHESES_LOGGED", "Perception"]

HYPOTHESES_LOGGED = 5  # hypotheses (most probable first) written with each match step


class Perception:
    """The session's detection log (kept in memory for matching, streamed to ``log_path``), and the
    sightings and confirmed features of the images recorded while ``detecting``."""

    def __init__(
        self,
        meta: Meta,
        log_path: Path | None,
        cmap: ClassMap,
        options: MatchOptions,
        drift_window: float,
        scan_every: int,
        landmarks: LandmarkTracker | None = None,
    ) -> None:
        self.meta = meta
        self.cmap = cmap
        self.options = options
        self.drift_window = drift_window  # m of recent path matched when the whole path fits nothing
        self.scan_every = scan_every  # control steps between logged scans (lidar.log_every)
        self.log = DetectionLog(path=log_path or Path("session.jsonl"), meta=meta, records=[], lines=[])
        self._writer = LogWriter(log_path) if log_path else None
        self.write(meta, keep=False)
        self.sightings: list[Sighting] = []
        self.frames = 0  # images recorded so far
        self.confirmed: list[ConfirmedFeature] = []
        self.filter = DetectionFilter(options.filter_params())  # Eq. 3, fed each image's sightings
        self._filtered = 0  # sightings fed to the filter so far
        self.detecting = True  # False from a coarse claim on (again True after a failed fine stage)
        self.path = PathEvidence()  # images and scans along the odometry path, for verification
        self.travel = 0.0  # m of odometry travel so far
        self._last_odom: Pose2D | None = None
        # the lidar landmarks (None: the site has none, or matching.landmarks is off): every logged
        # scan goes through the tracker, each landmark it confirms is logged as a feature record
        # (source lidar), which is what ``bim-init match`` reads back from the log
        self.landmarks = landmarks
        self.lidar: list[FeatureRecord] = []
        self._lidar_matched = 0  # landmarks the last new_features() call had seen

    def write(self, record: Record, keep: bool = True) -> None:
        """Write ``record`` to the log file; ``keep`` it in the in-memory log that matching reads."""
        if keep:
            self.log.records.append(record)
            self.log.lines.append(len(self.log.records) + 1)
        if self._writer is not None:
            self._writer.write(record)

    def rivals(
        self,
        site: Site,
        report: MatchReport,
        hypothesis: Hypothesis,
        extra: int,
        apart_m: float,
        apart_rad: float,
        alpha_factor: float = 1.0,
    ) -> tuple[int, list[Hypothesis]]:
        """The pose-distinct hypotheses (``apart_m`` / ``apart_rad`` from ``hypothesis``) with at least
        min_inliers matches that appear when ``extra`` more outliers are allowed than ``report``'s
        hypotheses were found with, and the distance tolerance alpha (Eq. 8) is ``alpha_factor``
        times wider: how many (a search stopped at its cap counts as many) and those found (most
        probable first; none past the cap)."""
        if extra <= 0 and alpha_factor <= 1.0:
            return 0, []
        opts = dataclasses.replace(
            report.options,
            max_outliers=max(report.outliers_allowed, report.options.max_outliers) + max(extra, 0),
            outlier_share=0.0,
            alpha=report.options.alpha * max(alpha_factor, 1.0),
        )
        wider = match_log(self.log, site, opts, self.cmap, self.sightings)
        if wider.overflow:
            return wider.n_hypotheses, []
        found = [
            h
            for h in wider.hypotheses
            if h.n_inliers >= self.options.min_inliers
            and (
                h.pose.distance_to(hypothesis.pose) > apart_m or h.pose.yaw_error(hypothesis.pose) > apart_rad
            )
        ]
        return len(found), found

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def record_frame(self, frame: SensorFrame, step: int) -> None:
        """Log one control period: odometry, truth, every ``scan_every``-th scan, the image's detections."""
        t = round(frame.t, 3)
        if self._last_odom is not None:
            self.travel += self._last_odom.distance_to(frame.odom)
        self._last_odom = frame.odom
        self.write(Odom(t, frame.odom.x, frame.odom.y, frame.odom.yaw))
        if frame.truth is not None:
            self.write(Truth(t, frame.truth.x, frame.truth.y, frame.truth.yaw))
        if frame.scan is not None and step % self.scan_every == 0:
            s = frame.scan
            ranges = tuple(np.round(np.asarray(s.ranges, dtype=float), 3).tolist())
            self.write(Scan(t, s.angle_min, s.angle_increment, s.range_max, ranges), keep=False)
            angles = s.angle_min + s.angle_increment * np.arange(len(ranges))
            self.path.add_scan(frame.odom, self.travel, angles, np.array(ranges, dtype=float), s.range_max)
            if self.landmarks is not None:
                scan = ScanInput(
                    t, frame.odom, np.array(ranges, dtype=float), s.angle_min, s.angle_increment, s.range_max
                )
                for rec in feature_records(self.landmarks.add_scan(scan)):
                    self.write(rec)
                    self.lidar.append(rec)
        if frame.detections is not None and self.detecting:
            record = Detections(t, frame.odom, tuple(frame.detections))
            self.write(record)
            self.path.add_image(frame.odom, self.travel)
            self.sightings.extend(
                image_sightings(
                    record,
                    self.frames,
                    self.cmap,
                    self.meta.camera,
                    self.meta.camera_pose,
                    self.options.edge_margin,
                )
            )
            self.frames += 1

    @property
    def n_features(self) -> int:
        """Confirmed features so far: the camera's and the lidar landmarks."""
        return len(self.confirmed) + len(self.lidar)

    def new_features(self) -> bool:
        """Feed the detection filter (Eq. 3) the sightings since the last call; True if it confirmed
        more features or the lidar confirmed more landmarks."""
        lidar_grew = len(self.lidar) > self._lidar_matched
        self._lidar_matched = len(self.lidar)
        if self._filtered == len(self.sightings):
            return lidar_grew
        for sighting in self.sightings[self._filtered :]:
            self.filter.add(sighting)
        self._filtered = len(self.sightings)
        confirmed = self.filter.result().features
        grew = len(confirmed) > len(self.confirmed)
        self.confirmed = confirmed
        return grew or lidar_grew

    def match(self, t: float, site: Site) -> MatchReport:
        """Algorithm 1 on the log so far, logged as a ``hypotheses`` record."""
        report = match_log(self.log, site, self.options, self.cmap, self.sightings)
        window = self.drift_window
        if report.n_hypotheses == 0 and window > 0 and len(report.features) > self.options.min_inliers:
            # Odometry drift: the oldest features no longer fit; match the recent ones
            # (``bim-init match --drift-window`` replays this).
            recent = match_log(
                self.log,
                site,
                dataclasses.replace(self.options, drift_window=window),
                self.cmap,
                self.sightings,
            )
            if recent.n_hypotheses > 0:
                report = recent
        self.write(
            HypothesesRecord(
                round(t, 3),
                {
                    "verdict": report.verdict,
                    "count": report.n_hypotheses,
                    "features": len(report.features),
                    "storey": report.storey,
                    "hypotheses": [
                        {
                            "matches": h.matches,
                            "cost": round(h.cost, 4),
                            "storey": h.storey,
                            "pose": [round(v, 4) for v in h.pose.as_tuple()],
                        }
                        for h in report.hypotheses[:HYPOTHESES_LOGGED]
                    ],
                },
            )
        )
        return report
