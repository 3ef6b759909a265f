"""``bim-init bag2log BAG -o LOG.jsonl``: a recorded ROS bag as a detection log (no ROS needed).

Exit codes: 0 written, 2 bad input (one line on stderr).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from bimkit.cli import fail, number_option
from bimkit.errors import InputError
from bimkit.outputs import OutputFile, check_outputs
from initcli.cli import PROG
from initcli.cli.progress import message_progress
from initcli.ros.convert import convert_bag
from initcli.ros.records import Bag2LogOptions

__all__ = ["bag2log"]


def bag2log(
    bag: Annotated[Path, typer.Argument(metavar="BAG", help="ROS 1 .bag, ROS 2 bag folder (.db3) or .mcap.")],
    out: Annotated[Path, typer.Option("-o", "--out", metavar="LOG.jsonl", help="Detection log to write.")],
    image_topic: Annotated[
        str | None, typer.Option("--image-topic", metavar="T", help="Colour Image or CompressedImage topic.")
    ] = None,
    detections_topic: Annotated[
        str | None,
        typer.Option(
            "--detections-topic", metavar="T", help="vision_msgs/Detection2DArray topic (robot's detector)."
        ),
    ] = None,
    depth_topic: Annotated[
        str | None,
        typer.Option("--depth-topic", metavar="T", help="Aligned depth Image (16UC1 mm or 32FC1 m)."),
    ] = None,
    camera_info_topic: Annotated[
        str | None, typer.Option("--camera-info-topic", metavar="T", help="sensor_msgs/CameraInfo topic.")
    ] = None,
    odom_topic: Annotated[
        str | None,
        typer.Option("--odom-topic", metavar="T", help="nav_msgs/Odometry topic [default: /tf odom->base]."),
    ] = None,
    scan_topic: Annotated[
        str | None, typer.Option("--scan-topic", metavar="T", help="sensor_msgs/LaserScan topic.")
    ] = None,
    base_frame: Annotated[
        str | None,
        typer.Option("--base-frame", metavar="F", help="Robot base frame [default: the odometry's child]."),
    ] = None,
    model: Annotated[
        str, typer.Option("--model", metavar="default|M.onnx", help="ONNX detector for colour images.")
    ] = "default",
    rate: Annotated[
        float | None,
        typer.Option(
            "--rate",
            metavar="HZ",
            help="Use at most this many images per second, (0, 1000].",
            callback=number_option("bim-init", above=0, maximum=1000),
        ),
    ] = None,
    class_names: Annotated[
        str | None,
        typer.Option(
            "--class-names",
            metavar="door,lift,stairs",
            help="Names of numeric class ids (0,1,2.. or 0=door,..).",
        ),
    ] = None,
) -> None:
    """Convert a recorded ROS bag into a detection log for ``bim-init match``."""
    from initcli.ros.bag_reader import parse_class_names

    try:
        check_outputs([bag, None if model == "default" else Path(model)], [OutputFile(out, "-o/--out")])
        options = Bag2LogOptions(
            image_topic=image_topic,
            detections_topic=detections_topic,
            depth_topic=depth_topic,
            camera_info_topic=camera_info_topic,
            odom_topic=odom_topic,
            scan_topic=scan_topic,
            base_frame=base_frame,
            model=model,
            rate=rate,
            class_names=parse_class_names(class_names),
        )
        with message_progress() as progress:
            records, stats = convert_bag(bag, out, options, progress)
    except InputError as exc:
        fail(PROG, exc)
    for warning in stats.warnings:
        typer.echo(f"bim-init: warning: {warning}", err=True)
    typer.echo(
        f"wrote {out}: {stats.images} images, {stats.objects} detections, {stats.odom} odom, "
        f"{stats.scans} scans "
        f"({stats.messages} messages in {stats.seconds:.1f} s)"
    )
