"""The localiser's poses of a bag (``bim-init watch``, ``bag2log --pose-topic``): a
PoseWithCovarianceStamped topic (``/amcl_pose`` by default) or, with ``--pose-topic tf``, the
``map -> odom`` transforms on /tf composed with the odometry at their stamps (what Nav2's
``map -> base_link`` is). Map frame, never re-based: the poses are where the localiser puts the
robot on its map."""

from __future__ import annotations

from collections.abc import Callable

from bimkit.errors import InputError
from initcli.core.geometry.se2 import Pose2D
from initcli.io.log_records import Localiser
from initcli.ros.records import POSE_FROM_TF, Bag2LogOptions, BagTopics

__all__ = ["localiser_records"]

MAP_FRAME = "map"  # REP 105


def localiser_records(
    samples: list[tuple[float, str, Pose2D]],
    tf_edges: list[tuple[float, str, str, Pose2D]],
    odom_at: Callable[[float], Pose2D | None],
    topics: BagTopics,
    options: Bag2LogOptions,
) -> list[Localiser]:
    """``samples`` (t, frame, pose) of the localiser's topic, or the /tf ``map -> odom`` edges
    composed with ``odom_at(t)`` (the odometry's own frame, not re-based); InputError when the
    chosen source holds none, or a pose is in a frame other than ``map``."""
    if options.pose_topic == POSE_FROM_TF:
        out = []
        for t, parent, _, map_odom in tf_edges:
            if parent != MAP_FRAME:
                continue
            odom = odom_at(t)
            if odom is not None:
                p = map_odom * odom
                out.append(Localiser(t, p.x, p.y, p.yaw))
        if not out:
            raise InputError("--pose-topic tf: no map -> odom transform on /tf within the odometry's time")
        return out
    if topics.localiser is None:
        return []
    if not samples:
        raise InputError(f"{topics.localiser.name}: no localiser pose message")
    frames = {f for _, f, _ in samples if f and f != MAP_FRAME}
    if frames:
        raise InputError(
            f"{topics.localiser.name}: poses in frame {', '.join(sorted(frames))}; the localiser's pose"
            f" must be in the {MAP_FRAME} frame (REP 105)"
        )
    return [Localiser(t, p.x, p.y, p.yaw) for t, _, p in sorted(samples, key=lambda s: s[0])]
