"""Bags without a camera: a LaserScan and odometry only, in every layout (MCAP, a sqlite3 db3 without
message definitions, ROS 1), the laser mounted off the base's centre and turned, no-returns of every
kind; and the bad scans and odometry refused by name."""

from __future__ import annotations

import math
import sqlite3

import numpy as np
import pytest

from bimkit.errors import InputError
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import Meta, Odom, Scan, read_log
from initcli.io.log_writer import write_log
from initcli.ros.bag_reader import bag_to_records
from initcli.ros.bag_writer import BagMessage, odometry, transform_stamped, write_bag
from initcli.ros.records import LASER_SCAN, ODOMETRY, TF_MESSAGE
from initcli.ros.tf import yaw_quaternion

ROOM = (-3.0, -2.0, 5.0, 4.0)  # x0, y0, x1, y1: the walls of a closed room (odom frame = room frame)
MOUNT = Pose2D(0.12, -0.05, math.pi / 2)  # a laser turned 90 degrees, off the base's centre
BEAMS = 720
RANGE_MIN, RANGE_MAX = 0.1, 12.0


def _ray(px: float, py: float, a: np.ndarray) -> np.ndarray:
    """Range from (px, py) along angles ``a`` to the room's walls."""
    c, s = np.cos(a), np.sin(a)
    x0, y0, x1, y1 = ROOM
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(c > 0, (x1 - px) / c, np.where(c < 0, (x0 - px) / c, np.inf))
        ty = np.where(s > 0, (y1 - py) / s, np.where(s < 0, (y0 - py) / s, np.inf))
    return np.minimum(tx, ty)


def _pose(t: float) -> Pose2D:
    return Pose2D(0.5 * t, 0.2 * t, 0.3 * t)


def _scan(t: float, ranges: np.ndarray, frame: str = "laser", inc: float | None = None) -> dict:
    inc = 2 * math.pi / BEAMS if inc is None else inc
    return {
        "header": {"stamp": {"sec": int(t), "nanosec": int(round((t % 1) * 1e9))}, "frame_id": frame},
        "angle_min": -math.pi,
        "angle_max": -math.pi + inc * (len(ranges) - 1),
        "angle_increment": inc,
        "time_increment": 0.0,
        "scan_time": 0.1,
        "range_min": RANGE_MIN,
        "range_max": RANGE_MAX,
        "ranges": np.asarray(ranges, dtype=np.float32),
        "intensities": np.zeros(0, dtype=np.float32),
    }


BAD = {3: math.inf, 4: math.nan, 5: 0.0, 6: 0.05, 7: 30.0}  # beam -> a no-return of each kind


def _messages(mount: Pose2D = MOUNT, odom_tf: bool = False, seconds: float = 4.0) -> list[BagMessage]:
    out = [
        BagMessage(
            "/tf_static",
            TF_MESSAGE,
            0.0,
            {
                "transforms": [
                    transform_stamped(0.0, "base_link", "base_scan_mount", (mount.x, 0.0, 0.1), (0, 0, 0, 1)),
                    transform_stamped(
                        0.0, "base_scan_mount", "laser", (0.0, mount.y, 0.08), yaw_quaternion(mount.yaw)
                    ),
                ]
            },
        )
    ]
    angles = -math.pi + 2 * math.pi / BEAMS * np.arange(BEAMS)
    for k in range(int(seconds * 20)):
        t = 0.05 * k + 1.0
        base = _pose(t - 1.0)
        if odom_tf:
            tf = transform_stamped(t, "odom", "base_link", (base.x, base.y, 0.0), yaw_quaternion(base.yaw))
            out.append(BagMessage("/tf", TF_MESSAGE, t, {"transforms": [tf]}))
        else:
            out.append(BagMessage("/odom", ODOMETRY, t, odometry(t, base)))
        if k % 2 == 0:  # 10 Hz
            laser = base * mount
            ranges = _ray(laser.x, laser.y, laser.yaw + angles)
            for i, v in BAD.items():
                ranges[i + 7 * k] = v
            out.append(BagMessage("/scan", LASER_SCAN, t, _scan(t, ranges)))
    return out


def _drop_definitions(bag) -> int:
    db = next(bag.glob("*.db3"))
    with sqlite3.connect(db) as con:
        return con.execute("DELETE FROM message_definitions").rowcount


def _write(tmp_path, fmt: str, messages: list[BagMessage]):
    bag = write_bag(tmp_path / {"mcap": "b.mcap", "sqlite3": "b", "ros1": "b.bag"}[fmt], messages)
    if fmt == "sqlite3":
        assert _drop_definitions(bag) >= 1
    return bag


def _wall_distance(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    x0, y0, x1, y1 = ROOM
    return np.minimum.reduce([np.abs(x - x0), np.abs(x - x1), np.abs(y - y0), np.abs(y - y1)])


def _check_scans_on_walls(records, tolerance: float) -> None:
    odom = {round(r.t, 6): r for r in records if isinstance(r, Odom)}
    scans = [r for r in records if isinstance(r, Scan)]
    assert scans
    for s in scans:
        o = odom[round(s.t, 6)]
        r = np.array(s.ranges)
        a = s.angle_min + s.angle_increment * np.arange(len(r))
        ok = np.isfinite(r)
        assert ok.sum() >= BEAMS - 2 * len(BAD) - 10
        assert (r[ok] < RANGE_MAX + 1.0).all()  # the 30 m beyond range_max is no return
        xb, yb = r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])
        c, sn = math.cos(o.yaw), math.sin(o.yaw)
        x, y = o.x + c * xb - sn * yb, o.y + sn * xb + c * yb
        assert np.percentile(_wall_distance(x, y), 95) < tolerance
        assert _wall_distance(x, y).max() < 3 * tolerance


@pytest.mark.parametrize("fmt", ["mcap", "sqlite3", "ros1"])
def test_lidar_only_bag_in_every_layout(tmp_path, fmt):
    records, stats = bag_to_records(_write(tmp_path, fmt, _messages()))
    meta = records[0]
    assert isinstance(meta, Meta) and meta.camera_absent and stats.camera_absent
    assert meta.lidar_mount is not None
    assert meta.lidar_mount.yaw == pytest.approx(math.pi / 2)
    assert (meta.lidar_mount.x, meta.lidar_mount.y) == pytest.approx((0.12, -0.05))
    assert stats.scans == 40 and stats.odom == 80 and stats.images == 0
    _check_scans_on_walls(records, 0.03)  # 0.5 degree bins at up to 8 m
    log = tmp_path / "log.jsonl"
    write_log(log, records)
    again = read_log(log)
    assert again.meta.camera_absent and not again.detections
    assert '"camera_absent":true' in log.read_text().splitlines()[0]


def test_lidar_turned_on_the_base_centre_is_exact(tmp_path):
    """A laser only turned: the angles shift, each no-return stays NaN where it was."""
    records, _ = bag_to_records(
        _write(tmp_path, "mcap", _messages(Pose2D(0.0, 0.0, -math.pi / 2), odom_tf=True))
    )
    scans = [r for r in records if isinstance(r, Scan)]
    assert len(scans[0].ranges) == BEAMS
    assert scans[0].angle_min == pytest.approx(math.pi / 2, abs=1e-6)  # -pi - pi/2, wrapped
    assert [i for i, r in enumerate(scans[0].ranges) if not math.isfinite(r)] == sorted(BAD)
    _check_scans_on_walls(records, 1e-3)


def _edit_scans(messages, edit):
    for m in messages:
        if m.topic == "/scan":
            edit(m.value)
    return messages


def test_scan_angle_increment_zero_is_refused(tmp_path):
    msgs = _edit_scans(_messages(seconds=1.0), lambda v: v.update(angle_increment=0.0))
    with pytest.raises(InputError, match=r"/scan \(message 1.*angle increment is 0"):
        bag_to_records(_write(tmp_path, "mcap", msgs))


def test_scan_count_disagreeing_with_its_span_is_refused(tmp_path):
    msgs = _edit_scans(_messages(seconds=1.0), lambda v: v.update(angle_max=v["angle_min"] + math.pi))
    with pytest.raises(InputError, match=r"/scan \(message 1.*720 ranges disagree with its angles"):
        bag_to_records(_write(tmp_path, "mcap", msgs))


def test_odometry_of_two_publishers_interleaved_is_refused(tmp_path):
    msgs = _messages(seconds=2.0)
    odoms = [m for m in msgs if m.topic == "/odom"]
    for m in odoms[1::2]:  # a second odometry, 2 m beside the first, stamped between
        m.value["pose"]["pose"]["position"]["x"] += 2.0
    with pytest.raises(InputError, match=r"/odom: the odometry zigzags between two tracks"):
        bag_to_records(_write(tmp_path, "mcap", msgs))


def test_odometry_of_two_child_frames_is_refused(tmp_path):
    msgs = _messages(seconds=2.0)
    for m in [m for m in msgs if m.topic == "/odom"][1::2]:
        m.value["child_frame_id"] = "base_footprint"
    with pytest.raises(InputError, match=r"/odom: odometry of 2 child frames"):
        bag_to_records(_write(tmp_path, "mcap", msgs))


def test_odometry_clock_stepping_back_is_refused(tmp_path):
    msgs = _messages(seconds=3.0)
    odoms = [m for m in msgs if m.topic == "/odom"]
    odoms[30].value["header"]["stamp"]["sec"] -= 2
    with pytest.raises(InputError, match=r"/odom: the clock jumps back"):
        bag_to_records(_write(tmp_path, "mcap", msgs))


def test_one_odometry_pose_a_kilometre_off_is_refused(tmp_path):
    msgs = _messages(seconds=2.0)
    odoms = [m for m in msgs if m.topic == "/odom"]
    odoms[17].value["pose"]["pose"]["position"]["x"] += 1000.0
    with pytest.raises(
        InputError, match=r"/odom: an odometry pose 1000\.\d m from the one before \(t=1\.850 s"
    ):
        bag_to_records(_write(tmp_path, "mcap", msgs))


def test_no_camera_and_no_scan_is_refused(tmp_path):
    msgs = [m for m in _messages(seconds=1.0) if m.topic != "/scan"]
    with pytest.raises(InputError, match=r"neither a camera .* nor a sensor_msgs/LaserScan"):
        bag_to_records(_write(tmp_path, "mcap", msgs))


def test_laser_frame_not_in_tf_static_is_refused(tmp_path):
    msgs = [m for m in _messages(seconds=1.0) if m.topic != "/tf_static"]
    with pytest.raises(InputError, match=r"no transform base_link -> laser"):
        bag_to_records(_write(tmp_path, "mcap", msgs))
