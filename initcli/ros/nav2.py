"""The result where Nav2 takes it: ``/initialpose`` (PoseWithCovarianceStamped), the hypotheses as a
PoseArray and the session state as a string, as rosbridge JSON messages; and the pose to send,
from a finished session (``summary.json`` and its ``session.jsonl``)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from bimkit.checks import check_number, read_json
from bimkit.errors import InputError
from bimkit.schemas import schema_path
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import HypothesesRecord, read_log
from initcli.ros.records import InitialPose
from initcli.ros.tf import yaw_quaternion

__all__ = [
    "covariance_6x6",
    "hypothesis_poses",
    "initial_pose_message",
    "pose_array_message",
    "pose_dict",
    "read_summary",
    "session_initial_pose",
    "stamp_dict",
    "state_message",
]

# 6x6 (x, y, z, roll, pitch, yaw) indices of the planar 3x3 (x, y, yaw); AMCL reads 0, 7 and 35.
_PLANAR = (0, 1, 5)


def covariance_6x6(cov: np.ndarray | list | None) -> tuple[float, ...]:
    """The 3x3 (x, y, yaw) covariance of fine tuning as ROS's row-major 6x6; zeros when unknown."""
    out = [0.0] * 36
    if cov is not None:
        c = np.asarray(cov, dtype=float).reshape(3, 3)
        for i, a in enumerate(_PLANAR):
            for j, b in enumerate(_PLANAR):
                out[6 * a + b] = float(c[i, j])
    return tuple(out)


def stamp_dict(t: float, ros1: bool = False) -> dict[str, int]:
    """A time as ROS 2 ``{sec, nanosec}`` or, ``ros1``, as ROS 1's ``{secs, nsecs}`` (what a ROS 1
    rosbridge reads; each bridge ignores the other's names)."""
    sec = math.floor(t)
    nanosec = int(round((t - sec) * 1e9))
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"secs": int(sec), "nsecs": nanosec} if ros1 else {"sec": int(sec), "nanosec": nanosec}


def pose_dict(x: float, y: float, yaw: float) -> dict[str, Any]:
    qx, qy, qz, qw = yaw_quaternion(yaw)
    return {"position": {"x": x, "y": y, "z": 0.0}, "orientation": {"x": qx, "y": qy, "z": qz, "w": qw}}


def initial_pose_message(pose: InitialPose, ros1: bool = False) -> dict[str, Any]:
    """``geometry_msgs/PoseWithCovarianceStamped`` as rosbridge JSON (``ros1``: ROS 1 stamp names)."""
    return {
        "header": {"stamp": stamp_dict(pose.stamp, ros1), "frame_id": pose.frame_id},
        "pose": {"pose": pose_dict(pose.x, pose.y, pose.yaw), "covariance": list(pose.covariance)},
    }


def pose_array_message(
    t: float, poses: list[Pose2D], frame_id: str = "map", ros1: bool = False
) -> dict[str, Any]:
    """``geometry_msgs/PoseArray`` of the hypotheses (base poses in the BIM/map frame)."""
    return {
        "header": {"stamp": stamp_dict(t, ros1), "frame_id": frame_id},
        "poses": [pose_dict(p.x, p.y, p.yaw) for p in poses],
    }


def state_message(state: str) -> dict[str, Any]:
    return {"data": state}


def hypothesis_poses(record: HypothesesRecord) -> list[Pose2D]:
    """The poses of a ``hypotheses`` record written by ``bim-init run``."""
    out = []
    for h in record.data.get("hypotheses", []):
        pose = h.get("pose") if isinstance(h, dict) else None
        if isinstance(pose, list) and len(pose) == 3:
            out.append(Pose2D(float(pose[0]), float(pose[1]), float(pose[2])))
    return out


def _pose_of(doc: dict[str, Any], where: str) -> Pose2D:
    try:
        pose = Pose2D(float(doc["x"]), float(doc["y"]), math.radians(float(doc["yaw_deg"])))
    except (KeyError, TypeError, ValueError):
        raise InputError(f"summary.json: '{where}' needs x, y and yaw_deg") from None
    for name, value, bound in (("x", pose.x, 1e6), ("y", pose.y, 1e6), ("yaw_deg", doc["yaw_deg"], 3600.0)):
        check_number(float(value), f"summary.json: {where}.{name}", minimum=-bound, maximum=bound)
    return pose


def session_initial_pose(summary: dict[str, Any], log_path: Path | None) -> InitialPose:
    """The pose to send for a finished session: a live session's ``published`` pose (the claim
    carried by odometry to the newest odometry, stamped on the robot's clock, its covariance
    grown); else ``summary["pose"]``, the pose at the session's end, stamped with the newest
    odometry of its log (session time; ``duration_s`` without a log).
    """
    if not summary.get("success") or not isinstance(summary.get("pose"), dict):
        reason = summary.get("reason", "no pose")
        raise InputError(f"the session did not initialise ({reason}): no pose to send")
    sent = summary.get("published")
    where, doc = ("published", sent) if isinstance(sent, dict) else ("pose", summary["pose"])
    pose = _pose_of(doc, where)
    try:
        cov = covariance_6x6(doc.get("covariance") if where == "published" else summary.get("covariance"))
        t = float(doc["stamp"]) if where == "published" else float(summary.get("duration_s", 0.0))
    except (KeyError, TypeError, ValueError):
        raise InputError(
            f"summary.json: '{where}': covariance must be 3x3 numbers and the stamp a number"
        ) from None
    if where == "pose" and log_path is not None and log_path.exists():
        odom = read_log(log_path).odom
        if odom:
            t = odom[-1].t
    return InitialPose(t, pose.x, pose.y, pose.yaw, cov)


SUMMARY_SCHEMA = schema_path("summary.schema.json")


def read_summary(path: Path) -> dict[str, Any]:
    """A ``summary.json`` checked against ``summary.schema.json`` (``"success": "false"`` is not a
    boolean, a pose needs its numbers) and its covariance a covariance (no negative variance)."""
    from bimkit.schemas import validate_document  # jsonschema, with messages naming the key

    doc = read_json(Path(path), "a bim-init run summary (summary.json)")  # bounded, every number finite
    if not isinstance(doc, dict) or "success" not in doc:
        raise InputError(f"{path}: not a bim-init run summary.json (no 'success')")
    validate_document(doc, SUMMARY_SCHEMA, str(path))
    cov = doc.get("covariance")
    if cov is not None:
        matrix = np.asarray(cov, dtype=float)
        variances = np.diag(matrix)
        if (variances < 0).any():
            k = int(np.argmax(variances < 0))
            raise InputError(f"{path}: covariance.{k}.{k}: {variances[k]:g} is a negative variance")
        if (
            not np.allclose(matrix, matrix.T, atol=1e-6)
            or np.linalg.eigvalsh((matrix + matrix.T) / 2).min() < -1e-6
        ):
            raise InputError(f"{path}: covariance: not a covariance (not symmetric positive semi-definite)")
    return doc
