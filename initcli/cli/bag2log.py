"""``bim-init bag2log BAG -o LOG.jsonl``: a recorded ROS bag as a detection log (no ROS needed).

Exit codes: 0 written, 2 bad input (one line on stderr).
"""

from __future__ import annotations

import contextlib
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer

from bimkit.checks import check_output_file
from bimkit.cli import fail, number_option
from bimkit.errors import InputError
from initcli.cli import PROG
from initcli.io.detection_log import Record, write_log
from initcli.ros.records import Bag2LogOptions, Bag2LogStats


def convert_bag(
    bag: Path, out: Path, options: Bag2LogOptions, show_progress: bool = False
) -> tuple[list[Record], Bag2LogStats]:
    """Read ``bag`` and write the log to ``out`` atomically (a progress bar on a terminal)."""
    from initcli.ros.bag_reader import bag_to_records

    if show_progress and sys.stderr.isatty():
        from initcli.cli.progress import count_bar

        with count_bar("bag2log") as bar:
            task = bar.add_task("messages", total=None)
            records, stats = bag_to_records(
                bag, options, lambda done, total: bar.update(task, completed=done, total=total)
            )
    else:
        records, stats = bag_to_records(bag, options)
    out = Path(out)
    tmp = out.with_name(f".{out.name}.partial")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        write_log(tmp, records)
        tmp.replace(out)
    except OSError as exc:
        with contextlib.suppress(OSError):  # a parent that is a file: there is nothing to remove
            tmp.unlink(missing_ok=True)
        raise InputError(f"{out}: cannot write the log: {exc.strerror or exc}") from None
    return records, stats


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
        check_output_file(out, "-o/--out")
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
        records, stats = convert_bag(bag, out, options, show_progress=True)
    except InputError as exc:
        fail(PROG, exc)
    for warning in stats.warnings:
        typer.echo(f"bim-init: warning: {warning}", err=True)
    typer.echo(
        f"wrote {out}: {stats.images} images, {stats.objects} detections, {stats.odom} odom, "
        f"{stats.scans} scans "
        f"({stats.messages} messages in {stats.seconds:.1f} s)"
    )


BAG_SUFFIXES = (".bag", ".mcap", ".db3")


def is_bag(path: Path) -> bool:
    """A ROS bag rather than a detection log: .bag, .mcap, .db3, or a ROS 2 bag folder."""
    return path.suffix.lower() in BAG_SUFFIXES or (path.is_dir() and (path / "metadata.yaml").exists())


@contextmanager
def log_or_bag(path: Path) -> Iterator[Path]:
    """``path`` itself for a detection log; for a bag, the log converted into a temporary folder."""
    if not is_bag(Path(path)):
        yield Path(path)
        return
    with tempfile.TemporaryDirectory(prefix="bim-init-bag2log-") as tmp:
        log = Path(tmp) / f"{Path(path).stem}.jsonl"
        convert_bag(Path(path), log, Bag2LogOptions(), show_progress=True)
        yield log
