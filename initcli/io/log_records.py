"""The records of the detection log, version 1 (:mod:`initcli.io.detection_log` reads and writes
them): typed dataclasses, one per record type, and the parsed log."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

from bimtools.site.records import CAMERA
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D

__all__ = [
    "DetectedObject",
    "DetectionLog",
    "Detections",
    "FeatureRecord",
    "HypothesesRecord",
    "LOG_VERSION",
    "Localiser",
    "Meta",
    "NO_CAMERA",
    "NO_MOUNT",
    "Odom",
    "RECORD_TYPES",
    "Record",
    "Scan",
    "State",
    "Truth",
]

LOG_VERSION = 1
# the camera of a log without one (Meta.camera_absent): a placeholder that sees nothing
NO_CAMERA = CameraIntrinsics(fx=1.0, fy=1.0, cx=0.5, cy=0.5, width=1, height=1)
NO_MOUNT = CameraMount(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
RECORD_TYPES = ("meta", "odom", "detections", "feature", "scan", "truth", "localiser", "state", "hypotheses")


@dataclass(frozen=True)
class Meta:
    camera: CameraIntrinsics
    camera_pose: CameraMount
    version: int = LOG_VERSION
    frame: str = "odom"
    depth_window: int | None = None
    source: str | None = None
    # no camera on the robot (a lidar-only bag or laser log): the file has no camera fields, ``camera``
    # and ``camera_pose`` are NO_CAMERA / NO_MOUNT, and the log holds no detections
    camera_absent: bool = False
    # the laser's mount on the base (x, y, yaw) the scans were carried from; informational: the
    # scan records are already in the base frame (initcli.io.laser)
    lidar_mount: Pose2D | None = None
    # written by ``bim-init run``: the storey the session matched against (None: every storey, or
    # not recorded) and the settings it matched and registered with, {"matching": {...},
    # "registration": {...}} (the fields of MatchOptions and RegistrationParams), which
    # ``bim-init match`` takes for the options its user did not give (initcli.match.recorded)
    storey: str | None = None
    settings: dict[str, Any] | None = field(default=None, compare=False, hash=False)


@dataclass(frozen=True)
class Odom:
    t: float
    x: float
    y: float
    yaw: float

    @property
    def pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, self.yaw)


@dataclass(frozen=True)
class DetectedObject:
    cls: str
    score: float
    bbox: tuple[float, float, float, float]
    depth: float | None  # None: no valid depth in the window


@dataclass(frozen=True)
class Detections:
    t: float
    pose: Pose2D
    objects: tuple[DetectedObject, ...] = ()


@dataclass(frozen=True)
class FeatureRecord:
    t: float
    cls: str
    x: float
    y: float
    source: str = CAMERA  # the sensor that found it: "camera" or "lidar" (bimtools.site.records.SENSORS)


@dataclass(frozen=True)
class Scan:
    t: float
    angle_min: float
    angle_increment: float
    range_max: float
    ranges: tuple[float, ...]  # nan for a missing reading (null in the file)


@dataclass(frozen=True)
class Truth:
    t: float
    x: float
    y: float
    yaw: float

    @property
    def pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, self.yaw)


@dataclass(frozen=True)
class Localiser:
    """The pose a tracking localiser (Nav2's AMCL) held, in the map (site) frame, as it published
    it: what ``bim-init watch`` checks."""

    t: float
    x: float
    y: float
    yaw: float

    @property
    def pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, self.yaw)


@dataclass(frozen=True)
class State:
    """Whatever ``bim-init run`` decided; ``data`` is the record without ``type``."""

    t: float | None
    data: dict[str, Any] = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class HypothesesRecord:
    t: float | None
    data: dict[str, Any] = field(default_factory=dict, compare=False)


Record = Union[Meta, Odom, Detections, FeatureRecord, Scan, Truth, Localiser, State, HypothesesRecord]  # noqa: UP007


@dataclass
class DetectionLog:
    """A parsed log: the meta record, the other records in time order, and what was skipped."""

    path: Path
    meta: Meta
    records: list[Record]
    lines: list[int]  # source line of each record
    warnings: list[str] = field(default_factory=list)
    skipped_bad: int = 0
    skipped_unknown: dict[str, int] = field(default_factory=dict)
    # per record type: how many records were sorted and those of the type (a session's log only
    # grows, and it is matched after every new feature: only the records since are sorted again)
    _typed: dict[type, tuple[int, list[Any]]] = field(default_factory=dict, repr=False, compare=False)

    def of_type(self, kind: type) -> list[Any]:
        seen, found = self._typed.get(kind, (0, []))
        if seen > len(self.records):  # records were removed: sort them all again
            seen, found = 0, []
        if seen < len(self.records):
            found = found + [r for r in self.records[seen:] if isinstance(r, kind)]
            self._typed[kind] = (len(self.records), found)
        return list(found)

    @property
    def odom(self) -> list[Odom]:
        return self.of_type(Odom)

    @property
    def detections(self) -> list[Detections]:
        return self.of_type(Detections)

    @property
    def features(self) -> list[FeatureRecord]:
        return self.of_type(FeatureRecord)

    @property
    def truth(self) -> list[Truth]:
        return self.of_type(Truth)

    @property
    def localiser(self) -> list[Localiser]:
        return self.of_type(Localiser)
