"""CARMEN laser logs (FLASER, ROBOTLASER1, ODOM; .log, .clf, gzipped) as detection logs, no camera:
the beams' geometry, no-returns, the laser's mount, stamps made increasing with one note, bad lines
refused by ``file:line``; and the real logs of ../shared/real_lidar when they are there."""

from __future__ import annotations

import gzip
import math
import time
from pathlib import Path

import numpy as np
import pytest

from bimkit.errors import InputError
from initcli.io.carmen import carmen_to_records, is_carmen
from initcli.io.detection_log import Meta, Odom, Scan, read_log
from initcli.io.log_writer import write_log

REAL_LIDAR = Path(__file__).resolve().parents[3].parent / "shared" / "real_lidar"
ROOM = (-3.0, -2.0, 6.0, 4.0)


def _ray(px, py, a):
    c, s = np.cos(a), np.sin(a)
    x0, y0, x1, y1 = ROOM
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(c > 0, (x1 - px) / c, np.where(c < 0, (x0 - px) / c, np.inf))
        ty = np.where(s > 0, (y1 - py) / s, np.where(s < 0, (y0 - py) / s, np.inf))
    return np.minimum(tx, ty)


def _poses(k):
    return [(0.3 * i, 0.1 * i, 0.05 * i) for i in range(k)]


def _flaser(n=180, k=20, stamps=None, max_range=81.91):
    lines = ["# a CARMEN log", "PARAM robot_frontlaser_offset 0.0 nohost 0"]
    step = math.pi / (n - 1) if n % 2 else math.pi / n
    for i, (x, y, th) in enumerate(_poses(k)):
        t = stamps[i] if stamps is not None else 10.0 + i
        lines.append(f"ODOM {x:.4f} {y:.4f} {th:.4f} 0 0 0 {t - 0.05:.3f} host {t - 0.05:.3f}")
        r = _ray(x, y, th - math.pi / 2 + step * np.arange(n))
        r[0], r[1] = max_range, 0.0  # nothing seen, no reading
        ranges = " ".join(f"{v:.3f}" for v in r)
        lines.append(f"FLASER {n} {ranges} {x} {y} {th} {x} {y} {th} {t:.3f} host {t:.3f}")
    return "\n".join(lines) + "\n"


def _write(tmp_path, text, name="run.log", zipped=False):
    path = tmp_path / (name + (".gz" if zipped else ""))
    data = text.encode()
    path.write_bytes(gzip.compress(data) if zipped else data)
    return path


def _check_on_walls(records, tol=0.01):
    odom = [r for r in records if isinstance(r, Odom)]
    scans = [r for r in records if isinstance(r, Scan)]
    times = [o.t for o in odom]
    start = (0.0, 0.0, 0.0)
    assert start == (odom[0].x, odom[0].y, odom[0].yaw)
    for s in scans:
        o = odom[int(np.searchsorted(times, s.t, side="right")) - 1]
        r = np.array(s.ranges)
        a = s.angle_min + s.angle_increment * np.arange(len(r))
        ok = np.isfinite(r)
        x = o.x + r[ok] * np.cos(o.yaw + a[ok])
        y = o.y + r[ok] * np.sin(o.yaw + a[ok])
        x0, y0, x1, y1 = ROOM
        d = np.minimum.reduce([abs(x - x0), abs(x - x1), abs(y - y0), abs(y - y1)])
        assert d.max() < tol


@pytest.mark.parametrize(("n", "step_deg"), [(180, 1.0), (360, 0.5), (361, 0.5)])
@pytest.mark.parametrize("zipped", [False, True])
def test_flaser_log(tmp_path, n, step_deg, zipped):
    path = _write(tmp_path, _flaser(n), "run.clf" if n == 361 else "run.log", zipped)
    assert is_carmen(path)
    records, stats = carmen_to_records(path)
    meta = records[0]
    assert isinstance(meta, Meta) and meta.camera_absent
    scans = [r for r in records if isinstance(r, Scan)]
    assert len(scans) == 20 == stats.scans and stats.odom == 40 and not stats.warnings
    s = scans[0]
    assert s.angle_min == pytest.approx(-math.pi / 2)
    assert math.degrees(s.angle_increment) == pytest.approx(step_deg)
    assert len(s.ranges) == n and s.range_max == pytest.approx(81.91)
    assert math.isnan(s.ranges[0]) and math.isnan(s.ranges[1])  # the maximum and 0: no returns
    _check_on_walls(records)
    write_log(tmp_path / "out.jsonl", records)
    assert read_log(tmp_path / "out.jsonl").meta.camera_absent


def test_odometry_from_the_laser_lines_without_odom_lines(tmp_path):
    text = "\n".join(line for line in _flaser().splitlines() if not line.startswith("ODOM"))
    records, stats = carmen_to_records(_write(tmp_path, text))
    assert stats.odom == 20
    _check_on_walls(records)


def test_robotlaser1_with_a_mount(tmp_path):
    """A laser 0.2 m ahead of the robot's centre: its beams carried to the base."""
    lines = []
    n, start, res = 181, -math.pi / 2, math.pi / 180
    for i, (x, y, th) in enumerate(_poses(15)):
        lx, ly = x + 0.2 * math.cos(th), y + 0.2 * math.sin(th)
        r = _ray(lx, ly, th + start + res * np.arange(n))
        r[5] = 30.0  # at the maximum range: no return
        ranges = " ".join(f"{v:.4f}" for v in r)
        lines.append(
            f"ROBOTLASER1 0 {start} {math.pi} {res} 30.0 0.01 0 {n} {ranges} 0 {lx} {ly} {th} {x} {y} {th} "
            f"0 0 0.5 0.5 0 {1.0 + i} host {1.0 + i}"
        )
    records, stats = carmen_to_records(_write(tmp_path, "\n".join(lines)))
    meta = records[0]
    assert meta.lidar_mount is not None and meta.lidar_mount.x == pytest.approx(0.2)
    assert stats.scans == 15
    _check_on_walls(records, tol=0.08)  # 1 degree bins up to 9 m


def test_bad_stamps_are_made_increasing_with_one_note(tmp_path):
    stamps = [5.0, 0.0, -3.0, 4.0, 4.0] + [6.0 + i for i in range(15)]
    records, stats = carmen_to_records(_write(tmp_path, _flaser(stamps=stamps)))
    times = [r.t for r in records[1:]]  # a scan and the odometry of its line share a stamp
    assert all(b >= a for a, b in zip(times, times[1:], strict=False)) and times[-1] > times[0]
    assert len(stats.warnings) == 1 and "not increasing; made increasing" in stats.warnings[0]


def _lines(text, edit):
    lines = text.splitlines()
    edit(lines)
    return "\n".join(lines)


def _replace(i, old, new):
    def edit(lines):
        lines[i] = lines[i].replace(old, new, 1)

    return edit


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        (
            _replace(3, "FLASER 180", "FLASER 200"),
            r":4: FLASER: \d+ fields, at least 209 expected \(200 ranges",
        ),
        (_replace(3, "FLASER 180", "FLASER x"), r":4: FLASER: the number of ranges 'x' is not an integer"),
        (_replace(3, "FLASER 180 ", "FLASER 180 abc "), r":4: FLASER range: 'abc' is not a number"),
        (_replace(4, "ODOM 0.3000", "ODOM 1000.3000"), r"an odometry pose 1000\.\d m .*\(line 5;"),
        (_replace(2, "ODOM 0.0000", "ODOM 1000.0000"), r"an odometry pose 1000\.\d m .*\(line 3;"),
        (_replace(2, "ODOM 0.0000", "ODOM nan"), r":3: ODOM: a pose that is not finite"),
        (lambda lines: lines.insert(3, "\x01garbage here"), r":4: not a CARMEN message"),
    ],
)
def test_bad_lines_name_file_and_line(tmp_path, edit, fragment):
    text = _lines(_flaser(k=5), edit)
    with pytest.raises(InputError, match=fragment):
        carmen_to_records(_write(tmp_path, text))


def _robotlaser(fov, res):
    return f"ROBOTLASER1 0 -1.5708 {fov} {res} 30 0.01 0 3 1 1 1 0 0 0 0 0 0 0 0 0 0 0 0 1.0 h 1.0\n"


@pytest.mark.parametrize(
    ("line", "fragment"),
    [
        (_robotlaser(3.1416, 0.0), r":1: ROBOTLASER1: a scan's angle increment is 0"),
        (_robotlaser(3.1416, 0.0175), r":1: ROBOTLASER1: a scan's 3 ranges disagree with its angles"),
    ],
)
def test_robotlaser1_geometry_refused(tmp_path, line, fragment):
    with pytest.raises(InputError, match=fragment):
        carmen_to_records(_write(tmp_path, line))


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (b"", "no FLASER or ROBOTLASER1 line"),
        (b"PARAM a b c\nODOM 0 0 0 0 0 0 1 h 1\n", "no FLASER or ROBOTLASER1 line"),
        (b"\x00\x01\x02binary", "not a text file"),
        (b"\x1f\x8b\x08garbage", "not a readable gzip file"),
    ],
)
def test_not_a_laser_log(tmp_path, content, fragment):
    path = tmp_path / "x.log"
    path.write_bytes(content)
    with pytest.raises(InputError, match=fragment):
        carmen_to_records(path)


REAL = sorted(REAL_LIDAR.glob("*.log.gz")) if REAL_LIDAR.is_dir() else []


@pytest.mark.skipif(not REAL, reason="../shared/real_lidar is absent")
@pytest.mark.parametrize("path", REAL, ids=lambda p: p.name)
def test_real_laser_logs(path):
    expected = {"intel": 910, "aces": 440, "csail": 406, "freiburg": 292}
    started = time.perf_counter()
    records, stats = carmen_to_records(path)
    assert time.perf_counter() - started < 3.0
    assert records[0].camera_absent
    scans = [r for r in records if isinstance(r, Scan)]
    name = path.name.split("-")[0]
    if name in expected:
        assert len(scans) == expected[name]
    assert all(math.degrees(s.angle_min) == pytest.approx(-90) for s in scans)
    times = [r.t for r in records[1:]]
    assert all(b >= a for a, b in zip(times, times[1:], strict=False))
    valid = np.concatenate([np.array(s.ranges) for s in scans])
    assert np.nanmax(valid) < scans[0].range_max  # the scanner's maximum is no return
