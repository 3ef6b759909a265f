"""``bim-init publish-pose SUMMARY.json``: send a finished session's pose to Nav2 over rosbridge.

``geometry_msgs/PoseWithCovarianceStamped`` on ``/initialpose``, frame ``map``: a live run's
``published`` pose (on the robot's clock, carried to its newest odometry), else the session's
final pose stamped at its newest odometry; the covariance (AMCL reads cov[0], cov[7], cov[35]).
Advertised first (rosapi or a delay), AMCL's ``set_initial_pose`` called where rosbridge offers
it, flushed before the link closes; ``--confirm S``: re-sent until AMCL's ``/amcl_pose`` agrees
or S seconds pass. ROS 1 stamps (``secs``/``nsecs``) with ``--ros1`` or when the live run's robot
stamped so. Exit codes: 0 sent (and confirmed, with ``--confirm``), 1 not confirmed, 2 bad input
or no rosbridge.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import typer

from bimkit.cli import fail, number_option
from bimkit.errors import InputError
from initcli.cli import PROG

__all__ = ["publish_pose"]


def publish_pose(
    summary: Annotated[Path, typer.Argument(metavar="SUMMARY.json", help="summary.json of bim-init run.")],
    host: Annotated[str, typer.Option("--host", metavar="HOST", help="rosbridge server.")] = "localhost",
    port: Annotated[
        int,
        typer.Option(
            "--port",
            metavar="PORT",
            help="rosbridge port, 1-65535.",
            callback=number_option("bim-init", minimum=1, maximum=65535),
        ),
    ] = 9090,
    ros1: Annotated[
        bool,
        typer.Option("--ros1", help="ROS 1 rosbridge: stamps as secs/nsecs [default: as the run's robot]."),
    ] = False,
    confirm: Annotated[
        float,
        typer.Option(
            "--confirm",
            metavar="S",
            help="Wait up to S s for /amcl_pose to agree (nav2.confirm defaults), re-sending; 0: no wait.",
            callback=number_option("bim-init", minimum=0, maximum=600),
        ),
    ] = 0.0,
    dry_run: Annotated[
        bool, typer.Option("--dry-run", help="Print the message as JSON instead of sending it.")
    ] = False,
) -> None:
    """Send the session's pose to /initialpose (Nav2/AMCL) over rosbridge."""
    from initcli.ros.nav2 import initial_pose_message, read_summary, session_initial_pose

    try:
        doc = read_summary(summary)
        pose = session_initial_pose(doc, summary.parent / "session.jsonl")
        old_style = ros1 or str((doc.get("clock") or {}).get("stamps", "")).startswith("ros1")
        if dry_run:
            typer.echo(json.dumps(initial_pose_message(pose, old_style), indent=2))
            return
        from initcli.config import Nav2Section
        from initcli.ros.delivery import publish_initial_pose

        settings = Nav2Section()
        settings.confirm.timeout = confirm
        report = publish_initial_pose(pose, host, port, settings, old_style)
    except InputError as exc:
        fail(PROG, exc)
    if not report.get("flushed", False):
        fail(
            PROG,
            f"ws://{host}:{port} did not answer after /initialpose was published: not known to be sent"
            " (a rosbridge server answers; is it one, and is it up?)",
        )
    verdict = {None: "", True: ", confirmed by AMCL", False: ", not confirmed by AMCL"}[report["confirmed"]]
    typer.echo(
        f"sent /initialpose to ws://{host}:{port} ({report['sends']}x{verdict}): "
        f"x {pose.x:.3f} y {pose.y:.3f} yaw {math.degrees(pose.yaw):.2f} deg at t {pose.stamp:.3f} s"
    )
    if report["confirmed"] is False:
        raise typer.Exit(1)
