"""The detection log, version 1, read and written (its records: :mod:`initcli.io.log_records`):
JSON Lines, one record per line, ordered by time ``t`` (seconds).

Schema: ``schemas/detection_log.schema.json`` (one line = one instance). Records:

- ``meta`` (first line): version 1, frame ``odom``, camera intrinsics, camera pose on the robot,
  optional ``depth_window`` n and ``source``; ``camera_absent: true`` instead of the camera fields
  when the robot had no camera (a lidar-only bag or laser log: no ``detections`` then), and
  optionally ``lidar_mount`` (x, y, yaw), the laser's mount the scans were carried from; a
  session's log (``bim-init run``) adds ``storey`` (the storey it matched; absent: every storey)
  and ``settings`` (``matching`` and ``registration``: what it matched and registered with).
- ``scan``: a planar scan in the robot's base frame (beams from the base origin, angle 0 along the
  base's x axis; null: no return), see :mod:`initcli.io.laser`.
- ``odom``: robot pose (x, y, yaw) in the odometry frame (origin: start pose, x: initial heading).
- ``detections``: one image's raw detector output, with the odom pose when it was taken; each
  object has ``class``, ``score``, ``bbox`` [u1, v1, u2, v2] and ``depth`` (mean over the
  (2n+1)x(2n+1) window at the box centre).
- ``feature`` (optional): an already aggregated feature in the odom frame; ``source`` says which
  sensor found it: ``camera`` (the default: a log without the field is a camera log) or ``lidar``
  (a wall corner, column corner or opening, see :mod:`initcli.core.lidar.landmark_tracks`).
- ``truth`` (optional, simulation only: true pose in the BIM frame).
- ``localiser`` (optional): the pose a tracking localiser (AMCL) published, in the map (site)
  frame: what ``bim-init watch`` checks (``bag2log --pose-topic``).
- ``state``, ``hypotheses`` (optional, written by ``bim-init run``): kept as plain data.

Unknown record types are skipped with one warning (forward compatibility); unknown keys in a
known record are ignored. A malformed line raises :class:`bimkit.errors.InputError` naming
``file:line`` and the problem, or is skipped and counted with ``skip_bad=True``.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bimkit.documents import check_finite_tree, parse_json, read_bytes
from bimkit.errors import InputError
from bimkit.limits import MAX_LOG_BYTES, MAX_LOG_LINE_BYTES, show_bytes
from bimtools.site.records import CAMERA, SENSORS
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.io.log_records import (
    LOG_VERSION,
    NO_CAMERA,
    NO_MOUNT,
    RECORD_TYPES,
    DetectedObject,
    DetectionLog,
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

__all__ = [
    "is_detection_log",
    "read_meta",
    "MAX_ANGLE",
    "MAX_COORDINATE",
    "MAX_TIME",
    "parse_record",
    "read_log",
]


class _Bad(ValueError):
    """A problem with one line (message without the file:line prefix)."""


# --- field readers ---------------------------------------------------------------------------------


def _num(obj: dict[str, Any], key: str, where: str = "") -> float:
    if key not in obj:
        raise _Bad(f"missing field {where}{key!r}")
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise _Bad(f"field {where}{key!r} must be a number, got {json.dumps(v)}")
    if isinstance(v, int) and abs(v) > 2**1000:
        raise _Bad(f"field {where}{key!r} is too large a number")
    if not math.isfinite(v):
        raise _Bad(f"field {where}{key!r} must be finite, got {v}")
    return float(v)


MAX_COORDINATE = 1e6  # m: odometry, poses and features in the log (a building is far smaller)
MAX_ANGLE = 1e4  # rad: headings (unwrapped odometry yaw may grow, but not without bound)
MAX_TIME = 1e10  # s
MAX_META_LINE = 1 << 20  # bytes of a log's first line read to tell a detection log


def _coord(
    obj: dict[str, Any], key: str, where: str = "", bound: float = MAX_COORDINATE, unit: str = "m"
) -> float:
    """A finite number within +-bound (metres of odometry, radians of heading, seconds)."""
    v = _num(obj, key, where)
    if abs(v) > bound:
        raise _Bad(f"field {where}{key!r}: {v:g} {unit} is outside +-{bound:g} {unit}")
    return v


def _t(obj: dict[str, Any]) -> float:
    return _coord(obj, "t", bound=MAX_TIME, unit="s")


def _yaw(obj: dict[str, Any], where: str = "") -> float:
    return _coord(obj, "yaw", where, bound=MAX_ANGLE, unit="rad")


def _str(obj: dict[str, Any], key: str, where: str = "") -> str:
    if key not in obj:
        raise _Bad(f"missing field {where}{key!r}")
    v = obj[key]
    if not isinstance(v, str) or not v.strip():
        raise _Bad(f"field {where}{key!r} must be a non-empty string, got {json.dumps(v)}")
    return v


def _obj(obj: dict[str, Any], key: str) -> dict[str, Any]:
    if key not in obj:
        raise _Bad(f"missing field {key!r}")
    v = obj[key]
    if not isinstance(v, dict):
        raise _Bad(f"field {key!r} must be an object, got {json.dumps(v)[:40]}")
    return v


def _parse_meta(o: dict[str, Any]) -> Meta:
    if "version" not in o:
        raise _Bad("meta record has no 'version'")
    version = o["version"]
    if isinstance(version, bool) or version != LOG_VERSION:
        raise _Bad(
            f"unsupported detection log version {json.dumps(version)}; bim-init reads version {LOG_VERSION}"
        )
    frame = o.get("frame", "odom")
    if frame != "odom":
        raise _Bad(f"meta 'frame' must be \"odom\", got {json.dumps(frame)}")
    absent = o.get("camera_absent", False)
    if not isinstance(absent, bool):
        raise _Bad(f"'camera_absent' must be true or false, got {json.dumps(absent)}")
    if absent and "camera" not in o and "camera_pose" not in o:
        intr, mount = NO_CAMERA, NO_MOUNT
    else:
        intr, mount = _camera(o)
    depth_window = o.get("depth_window")
    if depth_window is not None and (
        isinstance(depth_window, bool) or not isinstance(depth_window, int) or depth_window < 0
    ):
        raise _Bad(f"'depth_window' must be a non-negative integer, got {json.dumps(depth_window)}")
    source = o.get("source")
    if source is not None and not isinstance(source, str):
        raise _Bad(f"'source' must be a string, got {json.dumps(source)}")
    lidar = None
    if o.get("lidar_mount") is not None:
        lm = _obj(o, "lidar_mount")
        lidar = Pose2D(
            _coord(lm, "x", "lidar_mount.", bound=10.0),
            _coord(lm, "y", "lidar_mount.", bound=10.0),
            _coord(lm, "yaw", "lidar_mount.", bound=MAX_ANGLE, unit="rad"),
        )
    storey = o.get("storey")
    if storey is not None and (not isinstance(storey, str) or not storey):
        raise _Bad(f"'storey' must be a storey's name, got {json.dumps(storey)[:40]}")
    settings = o.get("settings")
    if settings is not None and (
        not isinstance(settings, dict) or not all(isinstance(v, dict) for v in settings.values())
    ):
        raise _Bad("'settings' must be an object of objects ('matching', 'registration')")
    return Meta(
        camera=intr,
        camera_pose=mount,
        version=LOG_VERSION,
        frame="odom",
        depth_window=depth_window,
        source=source,
        camera_absent=absent,
        lidar_mount=lidar,
        storey=storey,
        settings=settings,
    )


def _camera(o: dict[str, Any]) -> tuple[CameraIntrinsics, CameraMount]:
    cam = _obj(o, "camera")
    intr = CameraIntrinsics(
        fx=_num(cam, "fx", "camera."),
        fy=_num(cam, "fy", "camera."),
        cx=_num(cam, "cx", "camera."),
        cy=_num(cam, "cy", "camera."),
        width=int(_num(cam, "width", "camera.")),
        height=int(_num(cam, "height", "camera.")),
    )
    if intr.fx <= 0 or intr.fy <= 0:
        raise _Bad("camera fx and fy must be positive")
    if intr.width <= 0 or intr.height <= 0:
        raise _Bad("camera width and height must be positive")
    cp = _obj(o, "camera_pose")
    mount = CameraMount(*(_num(cp, k, "camera_pose.") for k in ("x", "y", "z", "roll", "pitch", "yaw")))
    return intr, mount


def _parse_object(o: Any, i: int) -> DetectedObject:
    where = f"objects[{i}]."
    if not isinstance(o, dict):
        raise _Bad(f"objects[{i}] must be an object")
    bbox = o.get("bbox")
    if not isinstance(bbox, list) or len(bbox) != 4:
        raise _Bad(f"field {where}'bbox' must be a list of 4 numbers [u1, v1, u2, v2]")
    box = tuple(_coord({"v": b}, "v", f"{where}bbox.", bound=1e6, unit="px") for b in bbox)
    if box[2] < box[0] or box[3] < box[1]:
        raise _Bad(f"field {where}'bbox' must have u1 <= u2 and v1 <= v2, got {list(box)}")
    depth = o.get("depth", None)
    if depth is not None:
        depth = _coord(o, "depth", where, bound=1000.0)
        if depth < 0:
            raise _Bad(
                f"field {where}'depth': {depth:g} m is negative (a distance; null where none was valid)"
            )
    score = _num(o, "score", where)
    if not 0.0 <= score <= 1.0:
        raise _Bad(f"field {where}'score': {score:g} is outside [0, 1] (a detector's confidence)")
    return DetectedObject(cls=_str(o, "class", where), score=score, bbox=box, depth=depth)  # type: ignore[arg-type]


def _parse_body(kind: str, o: dict[str, Any]) -> Record:
    if kind == "odom":
        return Odom(_t(o), _coord(o, "x"), _coord(o, "y"), _yaw(o))
    if kind == "detections":
        pose = _obj(o, "pose")
        objects = o.get("objects")
        if not isinstance(objects, list):
            raise _Bad("field 'objects' must be a list")
        return Detections(
            _t(o),
            Pose2D(_coord(pose, "x", "pose."), _coord(pose, "y", "pose."), _yaw(pose, "pose.")),
            tuple(_parse_object(obj, i) for i, obj in enumerate(objects)),
        )
    if kind == "feature":
        source = o.get("source", CAMERA)
        if source not in SENSORS:
            raise _Bad(f"field 'source' must be one of {', '.join(SENSORS)}, got {json.dumps(source)}")
        return FeatureRecord(_t(o), _str(o, "class"), _coord(o, "x"), _coord(o, "y"), source)
    if kind == "scan":
        ranges = o.get("ranges")
        if not isinstance(ranges, list):
            raise _Bad("field 'ranges' must be a list")
        values: list[float] = []
        for r in ranges:
            if r is None:
                values.append(math.nan)
            elif isinstance(r, bool) or not isinstance(r, int | float):
                raise _Bad(f"field 'ranges' must hold numbers or null, got {json.dumps(r)}")
            else:
                values.append(float(r))
        return Scan(
            _num(o, "t"),
            _num(o, "angle_min"),
            _num(o, "angle_increment"),
            _num(o, "range_max"),
            tuple(values),
        )
    if kind == "truth":
        return Truth(_t(o), _coord(o, "x"), _coord(o, "y"), _yaw(o))
    if kind == "localiser":
        return Localiser(_t(o), _coord(o, "x"), _coord(o, "y"), _yaw(o))
    if kind in ("state", "hypotheses"):
        t = _num(o, "t") if "t" in o else None
        data = {k: v for k, v in o.items() if k != "type"}
        return State(t, data) if kind == "state" else HypothesesRecord(t, data)
    raise _Bad(f"unknown record type {kind!r}")  # not reached


def parse_record(o: Any) -> Record | None:
    """One decoded JSON value -> a record; None for an unknown (future) record type.

    Raises ``ValueError`` (with a message for the user) when the record is malformed.
    """
    if not isinstance(o, dict):
        raise _Bad(f"expected a JSON object, got {type(o).__name__}")
    kind = o.get("type")
    if not isinstance(kind, str):
        raise _Bad(
            "missing field 'type'"
            if kind is None
            else f"field 'type' must be a string, got {json.dumps(kind)}"
        )
    if kind == "meta":
        return _parse_meta(o)
    if kind not in RECORD_TYPES:
        return None
    return _parse_body(kind, o)


def is_detection_log(path: Path | str) -> bool:
    """Does the file start as a detection log does (its first line a meta record)? What ``-o``
    may write over: a log an earlier run wrote, never another file."""
    if not Path(path).is_file():
        return False
    try:
        with open(path, "rb") as f:
            first = f.readline(MAX_META_LINE)
        doc = json.loads(first)
    except (OSError, ValueError):
        return False
    return isinstance(doc, dict) and doc.get("type") == "meta" and "version" in doc


def read_meta(path: Path | str) -> Meta | None:
    """The log's meta record alone (its first line), or None when it cannot be read or is not one
    (:func:`read_log` then says what is wrong)."""
    if not Path(path).is_file():
        return None  # a pipe or a device is never opened here (it could block for ever)
    try:
        with open(path, encoding="utf-8-sig") as handle:
            for raw in handle:
                if raw.strip():
                    value = json.loads(raw) if len(raw) <= MAX_LOG_LINE_BYTES else None
                    if not isinstance(value, dict) or value.get("type") != "meta":
                        return None
                    return _parse_meta(value)
    except (OSError, ValueError, RecursionError, _Bad):
        return None
    return None


def _record_time(rec: Record) -> float | None:
    return None if isinstance(rec, Meta) else rec.t


def read_log(path: Path | str, skip_bad: bool = False) -> DetectionLog:
    """Read a detection log; raise :class:`InputError` (``file:line: problem``) on bad input."""
    path = Path(path)
    text = _read_text(path)
    got = _Lines()
    for number, raw in enumerate(text.splitlines(), start=1):
        if not raw.strip():
            continue
        got.saw_any = True
        try:
            got.add(path, number, raw)
        except _Bad as exc:
            if not skip_bad or _safe_type(raw) == "meta":  # a bad meta record is never skipped
                raise InputError(f"{path}:{number}: {exc}") from None
            got.bad.append(f"{path}:{number}: {exc}")

    if not got.saw_any:
        raise InputError(f"{path}: empty log (no records)")
    if got.meta is None:
        raise InputError(
            f'{path}: missing meta record (the first line must be {{"type":"meta","version":{LOG_VERSION}}})'
        )
    unknown, bad = got.unknown, got.bad
    log = DetectionLog(
        path=path,
        meta=got.meta,
        records=got.records,
        lines=got.lines,
        skipped_bad=len(bad),
        skipped_unknown=unknown,
    )
    if bad:
        log.warnings.append(f"skipped {len(bad)} malformed line(s) (--skip-bad); first: {bad[0]}")
    if unknown:
        kinds = ", ".join(f"{k!r} x{n}" for k, n in sorted(unknown.items()))
        log.warnings.append(f"{path}: skipped record(s) of unknown type: {kinds}")
    _one_clock(log)
    _sort_by_time(log)
    return log


def _one_clock(log: DetectionLog) -> None:
    """A log whose odometry moves while every record carries one and the same time has no clock:
    which odometry goes with which scan or image cannot be told. Refused by name. (A session that
    ended where it started, at once, writes a few records of one time and one pose: that is fine.)"""
    stamps = [t for t in (_record_time(r) for r in log.records) if t is not None]
    poses = {(r.x, r.y, r.yaw) for r in log.records if isinstance(r, Odom)}
    if len(set(stamps)) == 1 and len(poses) > 1:
        raise InputError(
            f"{log.path}: all {len(stamps)} records carry the one time t={stamps[0]:g}: the log has no"
            " clock (write each message's header stamp, the robot's clock)"
        )


def _read_text(path: Path) -> str:
    """The log's text, within :data:`MAX_LOG_BYTES`; InputError for a missing file, a folder, a
    device, a binary or an unreadable file."""
    if not os.path.lexists(path):
        raise InputError(f"{path}: no such file")
    data = read_bytes(path, "a detection log (.jsonl)", MAX_LOG_BYTES)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (UTF-8 JSON Lines expected)") from None


@dataclass
class _Lines:
    """The lines of a log read so far: the meta record, the other records with their line numbers,
    the records of unknown types counted, and the malformed lines skipped (``--skip-bad``)."""

    meta: Meta | None = None
    records: list[Record] = field(default_factory=list)
    lines: list[int] = field(default_factory=list)
    unknown: dict[str, int] = field(default_factory=dict)
    bad: list[str] = field(default_factory=list)
    saw_any: bool = False

    def add(self, path: Path, number: int, raw: str) -> None:
        """One non-empty line; ``_Bad`` when it is malformed, InputError when the meta record is missing."""
        value = _decode_line(raw, path, number)
        rec = parse_record(value)
        _finite(value)
        if rec is None:
            kind = str(value.get("type"))
            self.unknown[kind] = self.unknown.get(kind, 0) + 1
            return
        if isinstance(rec, Meta):
            if self.meta is not None:
                raise _Bad("a second meta record (only the first line may be meta)")
            if self.records:
                raise _Bad("the meta record must be the first record")
            self.meta = rec
            return
        if self.meta is None:
            raise InputError(
                f"{path}:{number}: missing meta record: the first record must be "
                f'{{"type":"meta","version":{LOG_VERSION},...}}, got type {value.get("type")!r}'
            )
        if isinstance(rec, Detections) and self.meta.camera_absent:
            raise _Bad("a detections record in a log whose meta says camera_absent")
        self.records.append(rec)
        self.lines.append(number)


def _sort_by_time(log: DetectionLog) -> None:
    """Records out of time order sorted by t (with a warning); records without t keep their place
    relative to their neighbours as well as possible."""
    records, lines = log.records, log.lines
    times = [_record_time(r) for r in records]
    out_of_order = sum(
        1 for a, b in zip(times, times[1:], strict=False) if a is not None and b is not None and b < a
    )
    if out_of_order:
        log.warnings.append(f"{log.path}: {out_of_order} record(s) out of time order; sorted by t")
        order = sorted(
            range(len(records)), key=lambda i: (times[i] if times[i] is not None else -math.inf, i)
        )
        log.records = [records[i] for i in order]
        log.lines = [lines[i] for i in order]


def _decode_line(raw: str, path: Path, number: int) -> Any:
    """One line's JSON value, within the limits of :func:`bimkit.documents.parse_json` (depth,
    integer digits, no NaN or infinity anywhere) and :data:`MAX_LOG_LINE_BYTES`."""
    if len(raw) > MAX_LOG_LINE_BYTES:
        raise _Bad(f"a line of {show_bytes(len(raw))} (at most {show_bytes(MAX_LOG_LINE_BYTES)})")
    try:
        return parse_json(raw, str(path), line=number, finite=False)
    except InputError as exc:
        raise _Bad(str(exc).removeprefix(f"{path}:{number}: ")) from None


def _finite(value: Any) -> None:
    """NaN or infinity anywhere in a record (the fields read check their own): a bad line."""
    try:
        check_finite_tree(value, "")
    except InputError as exc:
        raise _Bad(str(exc).removeprefix(": ")) from None


def _safe_type(raw: str) -> str | None:
    try:
        value = json.loads(raw) if len(raw) <= MAX_LOG_LINE_BYTES else None
    except (ValueError, RecursionError):
        return None
    return value.get("type") if isinstance(value, dict) else None


# --- writer ----------------------------------------------------------------------------------------
