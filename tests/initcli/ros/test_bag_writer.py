"""Bags out: a simulated session as a ROS 2 MCAP, and the round trip sim -> bag -> bag2log -> match."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from initcli.cli.main import app
from initcli.io.detection_log import read_log
from initcli.io.log_writer import write_log
from initcli.match.pipeline import MatchOptions, run_match
from initcli.ros.bag_reader import bag_to_records
from initcli.ros.bag_source import BagSource
from initcli.ros.tf import quaternion_yaw
from tests.helpers import replayed_claim

runner = CliRunner()
SAMPLES = Path(__file__).resolve().parents[3] / "sample_models"


@pytest.fixture(scope="module")
def session(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("session")
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / "block_a.ifc")
    config = tmp / "block_a.yaml"
    config.write_text(yaml.safe_dump(doc))
    result = runner.invoke(
        app,
        [
            "run",
            "--config",
            str(config),
            "--out",
            str(tmp / "out"),
            "--quiet",
            "--start",
            "10.0,11.0,0",
            "--seed",
            "3",
            "--record",
            str(tmp / "session.mcap"),
        ],
    )
    assert result.exit_code == 0, result.output
    return tmp


def test_round_trip_gives_the_same_verdict_and_pose(session):
    site = session / "out" / "site"
    direct = run_match(session / "out" / "session.jsonl", site, MatchOptions())
    records, stats = bag_to_records(session / "session.mcap")
    assert stats.without_depth == 0 and stats.outside_odometry == 0
    write_log(session / "back.jsonl", records)
    back = run_match(session / "back.jsonl", site, MatchOptions())
    assert direct.verdict == back.verdict
    # what the session claimed (a unique match, the hypothesis the lidar along the path favours, or
    # the lidar registration's place)
    claim = replayed_claim(session / "out" / "session.jsonl", site, direct)
    again = replayed_claim(session / "back.jsonl", site, back)
    summary = json.loads((session / "out" / "summary.json").read_text())
    assert claim.matches == again.matches == summary["matched_ids"]
    a, b = claim.pose, again.pose
    assert a.distance_to(b) < 1e-3 and abs(a.yaw_error(b)) < 1e-4
    # the command line takes the bag in place of the log
    cli = runner.invoke(app, ["match", str(session / "session.mcap"), "--site", str(site), "--json"])
    doc = json.loads(cli.stdout)
    assert doc["paper_verdict"] == direct.verdict and cli.exit_code == doc["exit_code"], cli.output
    if direct.verdict != "unique match":  # several: the lidar (along the path, or a registration)
        assert doc["verdict"] == "unique match" and doc["decided_by"] == summary["decided_by"]
        assert doc["hypotheses"][0]["matches"] == claim.matches


def test_session_bag_topics_and_initialpose(session):
    summary = json.loads((session / "out" / "summary.json").read_text())
    with BagSource(session / "session.mcap") as bag:
        types = {t.name: t.msgtype for t in bag.topics.values()}
        assert types["/initialpose"] == "geometry_msgs/msg/PoseWithCovarianceStamped"
        assert types["/map"] == "nav_msgs/msg/OccupancyGrid"
        assert types["/bim_init/hypotheses"] == "geometry_msgs/msg/PoseArray"
        for topic in (
            "/odom",
            "/tf",
            "/tf_static",
            "/scan",
            "/camera/color/camera_info",
            "/camera/detections",
        ):
            assert topic in types
        (pose,) = [m for _, _, m in bag.messages(["/initialpose"])]
        grid = next(m for _, _, m in bag.messages(["/map"]))
    assert pose.header.frame_id == "map"
    cov = pose.pose.covariance
    want = summary["covariance"]
    assert (cov[0], cov[7], cov[35]) == pytest.approx((want[0][0], want[1][1], want[2][2]))
    assert cov[1] == pytest.approx(want[0][1]) and cov[5] == pytest.approx(want[0][2])
    # the final pose (the session ends on its claim) stamped at the newest odometry, not the last image
    log = read_log(session / "out" / "session.jsonl")
    stamp = pose.header.stamp.sec + pose.header.stamp.nanosec * 1e-9
    assert stamp == pytest.approx(log.odom[-1].t, abs=1e-6) and stamp > log.detections[-1].t
    p, q = pose.pose.pose.position, pose.pose.pose.orientation
    final = summary["pose"]
    assert (p.x, p.y) == pytest.approx((final["x"], final["y"]), abs=1e-4)
    assert math.degrees(quaternion_yaw(q.x, q.y, q.z, q.w)) == pytest.approx(final["yaw_deg"], abs=1e-3)
    assert grid.info.width > 0 and len(grid.data) == grid.info.width * grid.info.height
    assert set(grid.data.tolist()) <= {-1, 0, 100} and 100 in set(grid.data.tolist())


def _norm(q) -> float:
    return math.sqrt(q.x**2 + q.y**2 + q.z**2 + q.w**2)


def test_session_bag_qos_quaternions_and_map_to_odom_from_the_claim_on(session):
    log = read_log(session / "out" / "session.jsonl")
    claim_t = next(r.t for r in log.records if getattr(r, "data", {}).get("state") in ("fine", "done"))
    with BagSource(session / "session.mcap") as bag:
        qos = {c.topic: c.ext.offered_qos_profiles for c in bag.reader.connections}
        map_odom = [
            (tr.header.stamp.sec + tr.header.stamp.nanosec * 1e-9, tr)
            for _, _, m in bag.messages(["/tf"])
            for tr in m.transforms
            if tr.header.frame_id == "map"
        ]
        detections = [m for _, _, m in bag.messages(["/camera/detections"])]
        static = [tr for _, _, m in bag.messages(["/tf_static"]) for tr in m.transforms]
    for topic in ("/tf_static", "/map"):  # latched under ros2 bag play
        (profile,) = qos[topic]
        assert profile.durability.name == "TRANSIENT_LOCAL" and profile.depth == 1
    assert qos["/odom"][0].durability.name == "VOLATILE" and qos["/odom"][0].reliability.name == "RELIABLE"
    assert all(len(qos[t]) == 1 for t in qos)
    assert map_odom and min(t for t, _ in map_odom) == pytest.approx(claim_t, abs=0.06)
    assert max(t for t, _ in map_odom) == pytest.approx(log.odom[-1].t, abs=1e-6)
    assert all(tr.child_frame_id == "odom" for _, tr in map_odom)
    assert not [tr for tr in static if tr.header.frame_id == "map"]  # map -> odom is not static
    quaternions = [r.pose.pose.orientation for m in detections for d in m.detections for r in d.results]
    quaternions += [tr.transform.rotation for _, tr in map_odom] + [tr.transform.rotation for tr in static]
    assert quaternions and all(_norm(q) == pytest.approx(1.0) for q in quaternions)
