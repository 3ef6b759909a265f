"""``bim-init publish-pose SUMMARY.json``: send a finished session's pose to Nav2 once, over rosbridge.

``geometry_msgs/PoseWithCovarianceStamped`` on ``/initialpose``, frame ``map``, stamped at the
last image of the session (its ``session.jsonl`` beside the summary), the base frame's pose, the
covariance from fine tuning (AMCL reads cov[0], cov[7], cov[35]). Exit codes: 0 sent, 2 bad input
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
    dry_run: Annotated[
        bool, typer.Option("--dry-run", help="Print the message as JSON instead of sending it.")
    ] = False,
) -> None:
    """Send the session's pose once to /initialpose (Nav2/AMCL) over rosbridge."""
    from initcli.ros.nav2 import initial_pose_message, read_summary, session_initial_pose

    try:
        doc = read_summary(summary)
        pose = session_initial_pose(doc, summary.parent / "session.jsonl")
        if dry_run:
            typer.echo(json.dumps(initial_pose_message(pose), indent=2))
            return
        from initcli.ros.rosbridge import publish_initial_pose

        publish_initial_pose(pose, host, port)
    except InputError as exc:
        fail(PROG, exc)
    typer.echo(
        f"sent /initialpose to ws://{host}:{port}: x {pose.x:.3f} y {pose.y:.3f} "
        f"yaw {math.degrees(pose.yaw):.2f} deg at t {pose.stamp:.3f} s"
    )
