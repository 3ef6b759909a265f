"""initcli.ros.nav2: the rosbridge messages Nav2 reads and the pose sent from a finished session."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from bimkit.errors import InputError
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import Detections, HypothesesRecord, Meta, Odom
from initcli.io.log_writer import write_log
from initcli.ros.nav2 import (
    covariance_6x6,
    hypothesis_poses,
    initial_pose_message,
    pose_array_message,
    read_summary,
    session_initial_pose,
    stamp_dict,
    state_message,
)
from initcli.ros.records import InitialPose


def test_covariance_layout_puts_x_y_yaw_where_amcl_reads_them() -> None:
    c = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]])
    out = covariance_6x6(c)
    assert len(out) == 36
    assert (out[0], out[7], out[35]) == (1.0, 5.0, 9.0)
    assert (out[1], out[5], out[6], out[11], out[30], out[31]) == (2.0, 3.0, 4.0, 6.0, 7.0, 8.0)
    used = {0, 1, 5, 6, 7, 11, 30, 31, 35}
    assert all(out[i] == 0.0 for i in range(36) if i not in used)


def test_covariance_unknown_is_all_zero_and_flat_list_accepted() -> None:
    assert covariance_6x6(None) == (0.0,) * 36
    assert covariance_6x6([0.1, 0, 0, 0, 0.2, 0, 0, 0, 0.3])[35] == pytest.approx(0.3)


def test_stamp_dict_splits_seconds_and_carries_rounding() -> None:
    assert stamp_dict(12.25) == {"sec": 12, "nanosec": 250_000_000}
    assert stamp_dict(0.0) == {"sec": 0, "nanosec": 0}
    assert stamp_dict(3.9999999999) == {"sec": 4, "nanosec": 0}


def test_stamps_ros1_and_ros2_on_the_robots_clock() -> None:
    t = 1_700_000_123.25
    assert stamp_dict(t) == {"sec": 1_700_000_123, "nanosec": 250_000_000}
    assert stamp_dict(t, ros1=True) == {"secs": 1_700_000_123, "nsecs": 250_000_000}
    pose = InitialPose(t, 1.0, 2.0, 0.5, (0.0,) * 36)
    assert initial_pose_message(pose, ros1=True)["header"]["stamp"] == {
        "secs": 1_700_000_123,
        "nsecs": 250_000_000,
    }
    assert set(pose_array_message(t, [], ros1=True)["header"]["stamp"]) == {"secs", "nsecs"}


def test_initial_pose_message_quaternion_and_covariance() -> None:
    cov = covariance_6x6(np.diag([0.04, 0.09, 0.01]))
    msg = initial_pose_message(InitialPose(5.5, 1.0, -2.0, math.pi / 2, cov))
    assert msg["header"] == {"stamp": {"sec": 5, "nanosec": 500_000_000}, "frame_id": "map"}
    pose = msg["pose"]["pose"]
    assert pose["position"] == {"x": 1.0, "y": -2.0, "z": 0.0}
    q = pose["orientation"]
    assert (q["x"], q["y"]) == (0.0, 0.0)
    assert q["z"] == pytest.approx(math.sqrt(0.5)) and q["w"] == pytest.approx(math.sqrt(0.5))
    assert msg["pose"]["covariance"][0] == 0.04 and msg["pose"]["covariance"][7] == 0.09
    assert msg["pose"]["covariance"][35] == 0.01
    json.dumps(msg)  # plain JSON types only


def test_pose_array_and_state_messages() -> None:
    msg = pose_array_message(2.0, [Pose2D(1, 2, 0.0), Pose2D(3, 4, math.pi)], frame_id="bim")
    assert msg["header"]["frame_id"] == "bim"
    assert [p["position"]["x"] for p in msg["poses"]] == [1, 3]
    assert msg["poses"][1]["orientation"]["z"] == pytest.approx(1.0)
    assert state_message("matching") == {"data": "matching"}


def test_hypothesis_poses_keeps_only_well_formed_poses() -> None:
    record = HypothesesRecord(
        1.0,
        {"hypotheses": [{"pose": [1, 2, 0.5]}, {"pose": [1, 2]}, "junk", {"score": 3}, {"pose": [0, 0, 0]}]},
    )
    assert hypothesis_poses(record) == [Pose2D(1.0, 2.0, 0.5), Pose2D(0.0, 0.0, 0.0)]
    assert hypothesis_poses(HypothesesRecord(None, {})) == []


def _summary(**over: object) -> dict:
    doc = {"success": True, "pose": {"x": 4.0, "y": 1.0, "yaw_deg": 90.0}, "duration_s": 30.0}
    doc.update(over)
    return doc


def test_session_initial_pose_without_log_is_final_pose_at_duration() -> None:
    pose = session_initial_pose(_summary(covariance=np.diag([0.1, 0.2, 0.3]).tolist()), None)
    assert pose.stamp == 30.0
    assert (pose.x, pose.y) == (4.0, 1.0) and pose.yaw == pytest.approx(math.pi / 2)
    assert (pose.covariance[0], pose.covariance[7], pose.covariance[35]) == (0.1, 0.2, 0.3)


def test_session_initial_pose_is_the_final_pose_at_the_newest_odometry_not_the_last_image(
    tmp_path: Path,
) -> None:
    meta = Meta(CameraIntrinsics(500, 500, 320, 240, 640, 480), CameraMount(0, 0, 1, 0, 0, 0))
    odom = [Odom(float(t), float(t), 0.0, 0.0) for t in range(5)]  # 1 m/s along odom x
    image = Detections(2.0, Pose2D(2.0, 0.0, 0.0))
    log = tmp_path / "session.jsonl"
    write_log(log, [meta, *odom[:3], image, *odom[3:]])
    pose = session_initial_pose(_summary(), log)  # final (t=4): (4, 1) facing +y
    assert pose.stamp == 4.0  # not the last image's 2.0: the robot had moved on 2 m
    assert (pose.x, pose.y) == (4.0, 1.0) and pose.yaw == pytest.approx(math.pi / 2)


def test_session_initial_pose_of_a_live_run_is_what_was_published() -> None:
    published = {"stamp": 1_700_000_012.5, "x": 4.5, "y": 1.25, "yaw_deg": 95.0}
    published["covariance"] = np.diag([0.02, 0.03, 0.004]).tolist()
    pose = session_initial_pose(_summary(published=published, covariance=np.eye(3).tolist()), None)
    assert pose.stamp == 1_700_000_012.5 and (pose.x, pose.y) == (4.5, 1.25)
    assert pose.yaw == pytest.approx(math.radians(95.0))
    assert (pose.covariance[0], pose.covariance[7], pose.covariance[35]) == (0.02, 0.03, 0.004)
    with pytest.raises(InputError, match="published"):
        session_initial_pose(_summary(published={"x": 1.0}), None)


@pytest.mark.parametrize(
    "summary",
    [
        {"success": False, "reason": "distance limit"},
        {"success": True},
        {"success": True, "pose": {"x": 1.0, "y": 2.0}},
        {"success": True, "pose": {"x": 1e9, "y": 0.0, "yaw_deg": 0.0}},
        {"success": True, "pose": {"x": 0, "y": 0, "yaw_deg": 0}, "covariance": [1, 2]},
    ],
)
def test_session_initial_pose_refuses_bad_summaries(summary: dict) -> None:
    with pytest.raises(InputError):
        session_initial_pose(summary, None)


def test_read_summary(tmp_path: Path) -> None:
    good = tmp_path / "summary.json"
    good.write_text(json.dumps(_summary()))
    assert read_summary(good)["pose"]["x"] == 4.0
    bad = tmp_path / "other.json"
    bad.write_text(json.dumps({"pose": {}}))
    with pytest.raises(InputError, match="success"):
        read_summary(bad)


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ({"success": "false"}, r"success: expected true or false, got \"false\""),
        ({"success": 1}, r"success: expected true or false, got 1"),
        ({"pose": "here"}, r"pose: "),
        ({"pose": {"x": 4.0, "y": "5", "yaw_deg": 0}}, r"pose.y: expected a number, got \"5\""),
        ({"pose": None}, r"pose: "),
        (
            {"covariance": [[-0.1, 0, 0], [0, 0.2, 0], [0, 0, 0.3]]},
            r"covariance.0.0: -0.1 is a negative variance",
        ),
        ({"covariance": [[0.1, 5, 0], [0, 0.2, 0], [0, 0, 0.3]]}, r"covariance: not a covariance"),
        ({"covariance": [[0.1, 0], [0, 0.2]]}, r"covariance: "),
        ({"duration_s": -3}, r"duration_s: -3 is below the minimum 0"),
    ],
)
def test_a_summary_off_its_schema_is_refused_before_anything_is_sent(
    tmp_path: Path, change: dict, expected: str
) -> None:
    path = tmp_path / "summary.json"
    path.write_text(json.dumps({**_summary(), **change}))
    with pytest.raises(InputError, match=expected):
        read_summary(path)


def test_read_summary_checks_a_live_runs_published_pose(tmp_path: Path) -> None:
    path = tmp_path / "summary.json"
    published = {"stamp": 1_700_000_012.5, "x": 4.5, "y": 1.25, "yaw_deg": 95.0}
    path.write_text(json.dumps(_summary(published=published, delivery={"confirmed": True, "sends": 2})))
    assert read_summary(path)["published"]["stamp"] == 1_700_000_012.5
    path.write_text(json.dumps(_summary(published={"x": 4.5, "y": 1.25, "yaw_deg": 95.0})))
    with pytest.raises(InputError, match="published"):
        read_summary(path)
    path.write_text(json.dumps(_summary(delivery={"confirmed": "yes"})))
    with pytest.raises(InputError, match="delivery.confirmed"):
        read_summary(path)
