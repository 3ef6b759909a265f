"""``bim-init bag2log BAG -o LOG.jsonl``: a recorded ROS bag or a CARMEN laser log as a detection log
(no ROS needed).

Exit codes: 0 written, 2 bad input (one line on stderr).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer

from bimkit.cli import fail
from bimkit.errors import InputError
from bimkit.outputs import OutputFile, check_outputs
from initcli.cli import PROG
from initcli.cli.bag_options import (
    BaseFrame,
    CameraInfoTopic,
    ClassNames,
    DepthTopic,
    DetectionsTopic,
    ImageTopic,
    Model,
    OdomTopic,
    PoseTopic,
    Rate,
    ScanTopic,
    bag_options,
)
from initcli.cli.progress import message_progress
from initcli.io.detection_log import is_detection_log
from initcli.ros.convert import convert_bag

__all__ = ["bag2log"]


def _localiser(stats: object) -> str:
    n = getattr(stats, "localiser", 0)
    return f", {n} localiser poses" if n else ""


def bag2log(
    bag: Annotated[
        Path,
        typer.Argument(
            metavar="BAG",
            help="ROS 1 .bag, ROS 2 bag folder (.db3) or .mcap; or a CARMEN laser log (.log, .clf, .gz).",
        ),
    ],
    out: Annotated[Path, typer.Option("-o", "--out", metavar="LOG.jsonl", help="Detection log to write.")],
    image_topic: ImageTopic = None,
    detections_topic: DetectionsTopic = None,
    depth_topic: DepthTopic = None,
    camera_info_topic: CameraInfoTopic = None,
    odom_topic: OdomTopic = None,
    scan_topic: ScanTopic = None,
    base_frame: BaseFrame = None,
    pose_topic: PoseTopic = None,
    model: Model = "default",
    rate: Rate = None,
    class_names: ClassNames = None,
) -> None:
    """Convert a recorded ROS bag or a CARMEN laser log into a detection log for ``bim-init match``.
    A bag or log without a camera (a laser scan and odometry only) gives a log of scans and odometry
    whose meta says ``camera_absent``."""
    try:
        check_outputs(
            [bag, None if model == "default" else Path(model)],
            [OutputFile(out, "-o/--out", owned=is_detection_log, kind="detection log")],
        )
        options = bag_options(
            image_topic,
            detections_topic,
            depth_topic,
            camera_info_topic,
            odom_topic,
            scan_topic,
            base_frame,
            model,
            rate,
            class_names,
        )
        options = replace(options, pose_topic=pose_topic)
        with message_progress() as progress:
            records, stats = convert_bag(bag, out, options, progress)
    except InputError as exc:
        fail(PROG, exc)
    for warning in stats.warnings:
        typer.echo(f"bim-init: warning: {warning}", err=True)
    camera = "camera absent (lidar only), " if stats.camera_absent else ""
    typer.echo(
        f"wrote {out}: {camera}{stats.images} images, {stats.objects} detections, {stats.odom} odom, "
        f"{stats.scans} scans{_localiser(stats)} "
        f"({stats.messages} messages in {stats.seconds:.1f} s)"
    )
