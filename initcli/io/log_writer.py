"""The detection log, version 1, written: records as JSON lines, appended as a session goes
(:class:`LogWriter`) or all at once (:func:`write_log`); :mod:`initcli.io.detection_log` reads them."""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

from bimtools.site.records import CAMERA, LIDAR
from initcli.core.lidar.landmark_tracks import LidarLandmark
from initcli.io.log_records import (
    Detections,
    FeatureRecord,
    HypothesesRecord,
    Localiser,
    Meta,
    Odom,
    Record,
    Scan,
    State,
    Truth,
)

__all__ = ["LogWriter", "format_record", "iter_lines", "landmark_records", "record_to_dict", "write_log"]


def _meta_to_dict(rec: Meta) -> dict[str, Any]:
    c, m = rec.camera, rec.camera_pose
    out: dict[str, Any] = {"type": "meta", "version": rec.version, "frame": rec.frame}
    if rec.camera_absent:
        out["camera_absent"] = True
    else:
        out["camera"] = {
            "fx": c.fx,
            "fy": c.fy,
            "cx": c.cx,
            "cy": c.cy,
            "width": int(c.width),
            "height": int(c.height),
        }
        out["camera_pose"] = {
            "x": m.x,
            "y": m.y,
            "z": m.z,
            "roll": m.roll,
            "pitch": m.pitch,
            "yaw": m.yaw,
        }
    if rec.lidar_mount is not None:
        lm = rec.lidar_mount
        out["lidar_mount"] = {"x": lm.x, "y": lm.y, "yaw": lm.yaw}
    if rec.depth_window is not None:
        out["depth_window"] = int(rec.depth_window)
    if rec.source is not None:
        out["source"] = rec.source
    if rec.storey is not None:
        out["storey"] = rec.storey
    if rec.settings is not None:
        out["settings"] = rec.settings
    return out


def record_to_dict(rec: Record) -> dict[str, Any]:
    """A record as the JSON object of its line."""
    if isinstance(rec, Meta):
        return _meta_to_dict(rec)
    if isinstance(rec, Odom):
        return {"type": "odom", "t": rec.t, "x": rec.x, "y": rec.y, "yaw": rec.yaw}
    if isinstance(rec, Detections):
        return {
            "type": "detections",
            "t": rec.t,
            "pose": {"x": rec.pose.x, "y": rec.pose.y, "yaw": rec.pose.yaw},
            "objects": [
                {"class": o.cls, "score": o.score, "bbox": list(o.bbox), "depth": o.depth}
                for o in rec.objects
            ],
        }
    if isinstance(rec, FeatureRecord):
        out = {"type": "feature", "t": rec.t, "class": rec.cls, "x": rec.x, "y": rec.y}
        if rec.source != CAMERA:  # camera logs stay as they were
            out["source"] = rec.source
        return out
    if isinstance(rec, Scan):
        return {
            "type": "scan",
            "t": rec.t,
            "angle_min": rec.angle_min,
            "angle_increment": rec.angle_increment,
            "range_max": rec.range_max,
            "ranges": [None if not math.isfinite(r) else r for r in rec.ranges],
        }
    if isinstance(rec, Truth):
        return {"type": "truth", "t": rec.t, "x": rec.x, "y": rec.y, "yaw": rec.yaw}
    if isinstance(rec, Localiser):
        return {"type": "localiser", "t": rec.t, "x": rec.x, "y": rec.y, "yaw": rec.yaw}
    if isinstance(rec, State | HypothesesRecord):
        kind = "state" if isinstance(rec, State) else "hypotheses"
        out = {"type": kind, **{k: v for k, v in rec.data.items() if k != "type"}}
        if rec.t is not None:
            out["t"] = rec.t
        return out
    raise TypeError(f"not a detection log record: {rec!r}")


def format_record(rec: Record) -> str:
    """One line of the log (no newline)."""
    return json.dumps(record_to_dict(rec), separators=(",", ":"), allow_nan=False)


class LogWriter:
    """Append records to a log, one line each, flushing after every record (for ``bim-init run``)."""

    def __init__(self, target: Path | str | IO[str]) -> None:
        if isinstance(target, str | Path):
            self._handle: IO[str] = open(target, "w", encoding="utf-8")  # noqa: SIM115
            self._owned = True
        else:
            self._handle = target
            self._owned = False

    def write(self, rec: Record) -> None:
        self._handle.write(format_record(rec) + "\n")
        self._handle.flush()

    def write_all(self, records: Iterable[Record]) -> None:
        for rec in records:
            self.write(rec)

    def close(self) -> None:
        if self._owned:
            self._handle.close()

    def __enter__(self) -> LogWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def landmark_records(landmarks: Iterable[LidarLandmark]) -> list[FeatureRecord]:
    """Confirmed lidar landmarks as ``feature`` records with ``source: lidar``, at the time each was
    confirmed (their covariance and normal stay with the landmarks: the record has no field for them)."""
    return [FeatureRecord(float(m.t_confirmed), m.category, float(m.x), float(m.y), LIDAR) for m in landmarks]


def write_log(path: Path | str, records: Iterable[Record]) -> None:
    """Write a whole log (the first record must be the :class:`Meta`)."""
    with LogWriter(path) as writer:
        writer.write_all(records)


def iter_lines(records: Iterable[Record]) -> Iterator[str]:
    for rec in records:
        yield format_record(rec)
