"""A CARMEN laser log (``.log``, ``.clf``, either gzipped) -> detection-log records, no camera.

One message a line, fields separated by spaces; the lines read (every other kind is skipped):

- ``FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp``:
  n ranges over 180 degrees from -90 (right) counter-clockwise, 180/n degrees apart (180/(n-1) for
  an odd n: 181 or 361 beams reach +90); ``x y theta`` the laser's pose, ``odom_*`` the robot's.
- ``ROBOTLASER1 laser_type start_angle fov angular_res max_range accuracy remission_mode n r_1 .. r_n
  m rem_1 .. rem_m laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety
  side_safety turn_axis ipc_timestamp hostname logger_timestamp``.
- ``ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp``.

The odometry is the ODOM lines with the laser lines' robot poses among them (the laser lines' alone
when the log has no ODOM line, the ODOM lines alone when the two disagree), re-based so the log's
odom frame starts at the first pose. The laser's mount is the laser pose in the robot pose of its
lines (the same on every line, else the laser is taken as on the robot's centre, with a note). A
range at or above the scanner's maximum is no return: ROBOTLASER1 says its maximum; for FLASER it is
the largest range of the log when many beams read it (a scanner's "nothing seen" value), else none.
Time stamps (the ipc stamp) that are 0, negative, not finite or not increasing are made increasing
in the file's order, 1 ms after the one before, with one note.
"""

from __future__ import annotations

import gzip
import io
import math
import time
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bimkit.documents import read_bytes
from bimkit.errors import InputError
from bimkit.limits import MAX_LOG_BYTES, show_bytes
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.io.laser import check_odometry, check_scan_geometry, no_returns, scan_in_base
from initcli.io.log_records import NO_CAMERA, NO_MOUNT, Meta, Odom, Record, Scan

__all__ = [
    "CARMEN_SUFFIXES",
    "CarmenStats",
    "STAMP_STEP_S",
    "carmen_to_records",
    "is_carmen",
]

CARMEN_SUFFIXES = (".log", ".clf")  # and the same gzipped: .log.gz, .clf.gz
STAMP_STEP_S = 1e-3  # s: a stamp that is not increasing is put this long after the one before
MAX_STAMP_S = 1e10  # s: a larger stamp is no clock
MAX_BEAMS = 100_000
MOUNT_AGREE_M = 0.05  # m: the laser-in-robot poses of all lines within this of their median: one mount
MOUNT_AGREE_RAD = math.radians(2.0)
SATURATED = 0.99  # a FLASER range at or above this share of the log's largest is "nothing seen" ...
SATURATED_SHARE = 1e-4  # ... when at least this share of all beams (and 3) read it
FRAMES_DISAGREE_M = 1.0  # m: the laser lines' robot poses this far (median) from the ODOM lines'


@dataclass
class CarmenStats:
    """What a CARMEN log held, as ``bag2log`` reports a bag's (``images`` and ``objects`` stay 0)."""

    messages: int = 0  # lines read (FLASER, ROBOTLASER1, ODOM)
    images: int = 0
    objects: int = 0
    odom: int = 0
    scans: int = 0
    seconds: float = 0.0
    camera_absent: bool = True
    warnings: list[str] = field(default_factory=list)


def is_carmen(path: Path | str) -> bool:
    """A CARMEN log by its name: ``.log``, ``.clf``, ``.log.gz`` or ``.clf.gz`` (any case)."""
    name = Path(path).name.lower()
    name = name.removesuffix(".gz")
    return name.endswith(CARMEN_SUFFIXES)


def _text(path: Path) -> str:
    data = read_bytes(path, "a CARMEN log (.log, .clf, gzipped or not)", MAX_LOG_BYTES)
    if data[:2] == b"\x1f\x8b":
        try:
            with gzip.GzipFile(fileobj=io.BytesIO(data)) as handle:
                data = handle.read(MAX_LOG_BYTES + 1)
        except (OSError, EOFError, zlib.error) as exc:
            raise InputError(f"{path}: not a readable gzip file ({exc})") from None
        if len(data) > MAX_LOG_BYTES:
            raise InputError(f"{path}: more than {show_bytes(MAX_LOG_BYTES)} once unzipped")
    if b"\0" in data[:65536]:
        raise InputError(f"{path}: not a text file (a CARMEN log is text, one message a line)")
    return data.decode("latin-1")


class _Bad(ValueError):
    """A problem with one line (the message without ``file:line``)."""


def _floats(fields: list[str], what: str) -> np.ndarray:
    try:
        out = np.array(fields, dtype=float)
    except ValueError:
        bad = next((f for f in fields if not _is_number(f)), fields[0] if fields else "")
        raise _Bad(f"{what}: {bad[:20]!r} is not a number") from None
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _count(fields: list[str], i: int, what: str) -> int:
    if len(fields) <= i:
        raise _Bad(f"{what}: the line ends before the number of ranges")
    try:
        n = int(fields[i])
    except ValueError:
        raise _Bad(f"{what}: the number of ranges {fields[i][:20]!r} is not an integer") from None
    if n <= 0 or n > MAX_BEAMS:
        raise _Bad(f"{what}: {n} ranges (1 to {MAX_BEAMS})")
    return n


def _need(fields: list[str], count: int, what: str, n: int | None = None) -> None:
    if len(fields) < count:
        said = f" ({n} ranges said)" if n is not None else ""
        raise _Bad(f"{what}: {len(fields)} fields, at least {count} expected{said}")


@dataclass
class _Laser:
    line: int
    stamp: float
    angle_min: float
    angle_increment: float
    max_range: float | None  # None: FLASER (the log's largest range decides)
    ranges: np.ndarray
    laser: tuple[float, float, float]  # laser pose
    robot: tuple[float, float, float]  # robot (odometry) pose


@dataclass
class _Parsed:
    lasers: list[_Laser] = field(default_factory=list)
    odom: list[tuple[int, float, float, float, float]] = field(default_factory=list)  # line, stamp, x, y, th
    order: list[tuple[int, float]] = field(default_factory=list)  # every stamp in the file's order
    kinds: set[str] = field(default_factory=set)

    def flaser(self, number: int, f: list[str]) -> None:
        n = _count(f, 1, "FLASER")
        _need(f, n + 9, "FLASER", n)
        ranges = _floats(f[2 : 2 + n], "FLASER range")
        tail = _floats(f[2 + n : 2 + n + 7], "FLASER pose or time stamp")
        step = math.pi / (n - 1) if n % 2 == 1 and n > 1 else math.pi / n
        self._laser(number, tail[6], -math.pi / 2, step, None, ranges, tail[0:3], tail[3:6], "FLASER")

    def robotlaser(self, number: int, f: list[str]) -> None:
        _need(f, 9, "ROBOTLASER1")
        head = _floats(f[2:8], "ROBOTLASER1 header")
        start, fov, res, max_range = (float(v) for v in head[:4])
        n = _count(f, 8, "ROBOTLASER1")
        _need(f, 9 + n + 1, "ROBOTLASER1", n)
        ranges = _floats(f[9 : 9 + n], "ROBOTLASER1 range")
        m = _count_remissions(f, 9 + n)
        at = 10 + n + m
        _need(f, at + 12, "ROBOTLASER1", n)
        tail = _floats(f[at : at + 12], "ROBOTLASER1 pose, velocity or time stamp")
        check_scan_geometry("ROBOTLASER1", n, start, res, fov)
        if not (math.isfinite(max_range) and max_range > 0):
            raise _Bad(f"ROBOTLASER1: the maximum range {max_range:g} is not a positive number")
        self._laser(number, tail[11], start, res, max_range, ranges, tail[0:3], tail[3:6], "ROBOTLASER1")

    def _laser(
        self,
        number: int,
        stamp: float,
        angle_min: float,
        step: float,
        max_range: float | None,
        ranges: np.ndarray,
        laser: np.ndarray,
        robot: np.ndarray,
        what: str,
    ) -> None:
        if not (np.isfinite(laser).all() and np.isfinite(robot).all()):
            raise _Bad(f"{what}: a pose that is not finite")
        self.lasers.append(
            _Laser(
                number,
                float(stamp),
                angle_min,
                step,
                max_range,
                ranges,
                (float(laser[0]), float(laser[1]), float(laser[2])),
                (float(robot[0]), float(robot[1]), float(robot[2])),
            )
        )
        self.order.append((number, float(stamp)))

    def odometry(self, number: int, f: list[str]) -> None:
        _need(f, 8, "ODOM")
        try:
            x, y, th, stamp = float(f[1]), float(f[2]), float(f[3]), float(f[7])
        except ValueError:
            _floats(f[1:4] + f[7:8], "ODOM pose or time stamp")  # names the field
            raise
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(th)):
            raise _Bad("ODOM: a pose that is not finite")
        self.odom.append((number, stamp, x, y, th))
        self.order.append((number, stamp))


def _count_remissions(f: list[str], i: int) -> int:
    try:
        m = int(f[i])
    except ValueError:
        raise _Bad(f"ROBOTLASER1: the number of remissions {f[i][:20]!r} is not an integer") from None
    if m < 0 or m > MAX_BEAMS:
        raise _Bad(f"ROBOTLASER1: {m} remissions (0 to {MAX_BEAMS})")
    return m


def _parse(path: Path, text: str) -> _Parsed:
    got = _Parsed()
    readers = {"FLASER": got.flaser, "ROBOTLASER1": got.robotlaser, "ODOM": got.odometry}
    for number, raw in enumerate(text.split("\n"), start=1):
        fields = raw.split()
        if not fields or fields[0].startswith("#"):
            continue
        kind = fields[0]
        reader = readers.get(kind)
        if reader is None:
            if not kind.isupper() or not kind.replace("_", "").isalnum():
                raise InputError(f"{path}:{number}: not a CARMEN message (a line starts {kind[:20]!r})")
            got.kinds.add(kind)
            continue
        try:
            reader(number, fields)
        except _Bad as exc:
            raise InputError(f"{path}:{number}: {exc}") from None
        except InputError as exc:  # check_scan_geometry: "ROBOTLASER1: ..."
            raise InputError(f"{path}:{number}: {exc}") from None
    return got


def _monotonic(stamps: np.ndarray) -> tuple[np.ndarray, int]:
    """Stamps made increasing in order (a bad or not increasing one: 1 ms after the one before) and
    how many were changed."""
    out = np.empty(len(stamps))
    prev = -math.inf
    changed = 0
    for i, s in enumerate(stamps.tolist()):
        ok = math.isfinite(s) and 0 < s <= MAX_STAMP_S and s > prev
        if ok:
            prev = s
        else:
            changed += 1
            prev = STAMP_STEP_S if prev == -math.inf else prev + STAMP_STEP_S
        out[i] = prev
    return out, changed


def _relative(robot: np.ndarray, laser: np.ndarray) -> np.ndarray:
    """Each laser pose in its robot pose (rows x, y, theta)."""
    dx, dy = laser[:, 0] - robot[:, 0], laser[:, 1] - robot[:, 1]
    c, s = np.cos(robot[:, 2]), np.sin(robot[:, 2])
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, wrap_angle(laser[:, 2] - robot[:, 2])])


def _mount(path: Path, lasers: list[_Laser], notes: list[str]) -> Pose2D:
    """The laser's mount on the robot: the laser pose in the robot pose, if one for all lines."""
    rel = _relative(np.array([w.robot for w in lasers]), np.array([w.laser for w in lasers]))
    med = np.median(rel, axis=0)
    off = np.hypot(rel[:, 0] - med[0], rel[:, 1] - med[1])
    turn = np.abs(wrap_angle(rel[:, 2] - med[2]))
    if (off <= MOUNT_AGREE_M).all() and (turn <= MOUNT_AGREE_RAD).all():
        return Pose2D(float(med[0]), float(med[1]), float(med[2]))
    notes.append(
        f"{path}: the laser poses of the laser lines are not one mount on the robot poses (up to "
        f"{float(off.max()):.2f} m apart); the laser is taken as on the robot's centre, looking forward"
    )
    return Pose2D(0.0, 0.0, 0.0)


def _flaser_max(lasers: list[_Laser]) -> float | None:
    """The FLASER scanner's "nothing seen" range: the log's largest, when many beams read it."""
    flaser = [w.ranges for w in lasers if w.max_range is None]
    if not flaser:
        return None
    values = np.concatenate(flaser)
    values = values[np.isfinite(values)]
    if not values.size:
        return None
    top = float(values.max())
    if top <= 0:
        return None
    saturated = int((values >= SATURATED * top).sum())
    return top if saturated >= max(3, SATURATED_SHARE * values.size) else None


def carmen_to_records(path: Path | str) -> tuple[list[Record], CarmenStats]:
    """Read a CARMEN log into detection-log records (the :class:`Meta` first, then in time order);
    InputError naming ``file:line`` on bad input."""
    started = time.perf_counter()
    path = Path(path)
    parsed = _parse(path, _text(path))
    stats = CarmenStats(messages=len(parsed.order))
    if not parsed.lasers:
        kinds = ", ".join(sorted(parsed.kinds)) or "none"
        raise InputError(
            f"{path}: no FLASER or ROBOTLASER1 line (a CARMEN laser log; messages found: {kinds})"
        )
    line_stamp, changed = _monotonic(np.array([s for _, s in parsed.order]))
    t_of = {number: float(t) for (number, _), t in zip(parsed.order, line_stamp, strict=True)}
    if changed:
        stats.warnings.append(
            f"{path}: {changed} of {len(parsed.order)} time stamps were 0, negative or not increasing; "
            f"made increasing in the file's order ({STAMP_STEP_S * 1000:g} ms after the one before)"
        )
    mount = _mount(path, parsed.lasers, stats.warnings)
    odom = _odometry(path, parsed, t_of, stats.warnings)
    records: list[Odom | Scan] = _rebased(odom)
    flaser_max = _flaser_max(parsed.lasers)
    for w in parsed.lasers:
        reach = w.max_range if w.max_range is not None else flaser_max
        cutoff = math.inf if reach is None else reach if w.max_range is not None else SATURATED * reach
        ranges = no_returns(w.ranges, 0.0, cutoff)
        range_max = reach if reach is not None else float(np.nanmax(ranges, initial=0.0)) + 0.01
        records.append(scan_in_base(t_of[w.line], w.angle_min, w.angle_increment, range_max, ranges, mount))
    records.sort(key=lambda r: r.t)
    stats.odom, stats.scans = len(odom), len(parsed.lasers)
    read = sorted({"FLASER" if w.max_range is None else "ROBOTLASER1" for w in parsed.lasers})
    meta = Meta(
        camera=NO_CAMERA,
        camera_pose=NO_MOUNT,
        source=f"bim-init bag2log {path.name} (CARMEN log, no camera, {' and '.join(read)})",
        camera_absent=True,
        lidar_mount=mount,
    )
    stats.seconds = time.perf_counter() - started
    return [meta, *records], stats


def _rebased(odom: list[tuple[float, tuple[float, float, float]]]) -> list[Odom | Scan]:
    """Odom records in a frame whose origin is the first pose."""
    pose = np.array([p for _, p in odom], dtype=float)
    x0, y0, th0 = pose[0]
    dx, dy = pose[:, 0] - x0, pose[:, 1] - y0
    c, s = math.cos(th0), math.sin(th0)
    xs, ys, yaws = c * dx + s * dy, -s * dx + c * dy, wrap_angle(pose[:, 2] - th0)
    return [
        Odom(t, x, y, yaw)
        for (t, _), x, y, yaw in zip(odom, xs.tolist(), ys.tolist(), yaws.tolist(), strict=True)
    ]


def _odometry(
    path: Path, parsed: _Parsed, t_of: dict[int, float], notes: list[str]
) -> list[tuple[float, tuple[float, float, float]]]:
    """(t, robot pose) in the file's order: the ODOM lines with the laser lines' robot poses, or
    either alone (checked: no jump of a broken record)."""
    laser = [(w.line, w.robot) for w in parsed.lasers]
    odom = [(n, (x, y, th)) for n, _, x, y, th in parsed.odom]
    chosen = sorted(laser + odom) if odom else laser
    if odom and _frames_disagree(parsed):
        notes.append(
            f"{path}: the laser lines' robot poses are not in the ODOM lines' frame; the odometry is "
            "the ODOM lines'"
        )
        chosen = odom
    times = [t_of[n] for n, _ in chosen]
    xy = np.array([[p[0], p[1]] for _, p in chosen])
    check_odometry(str(path), times, xy, [f"line {n}" for n, _ in chosen])
    return [(t_of[n], p) for n, p in chosen]


def _frames_disagree(parsed: _Parsed) -> bool:
    """The laser lines' robot poses far (median) from the ODOM pose last before each."""
    lines = np.array([n for n, *_ in parsed.odom])
    xy = np.array([[x, y] for _, _, x, y, _ in parsed.odom])
    gaps = []
    for w in parsed.lasers:
        i = int(np.searchsorted(lines, w.line)) - 1
        if i >= 0:
            gaps.append(math.hypot(w.robot[0] - xy[i, 0], w.robot[1] - xy[i, 1]))
    return bool(gaps) and float(np.median(gaps)) > FRAMES_DISAGREE_M
