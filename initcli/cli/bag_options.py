"""The options that say how a ROS bag is read, shared by ``bim-init bag2log`` and ``bim-init match
BAG``: the topics, the base frame, the detector, the image rate and the names of numeric class ids."""

from __future__ import annotations

from typing import Annotated

import typer

from bimkit.cli import number_option
from initcli.ros.records import Bag2LogOptions

__all__ = [
    "BaseFrame",
    "CameraInfoTopic",
    "ClassNames",
    "DepthTopic",
    "DetectionsTopic",
    "ImageTopic",
    "Model",
    "OdomTopic",
    "PoseTopic",
    "Rate",
    "ScanTopic",
    "bag_options",
]

ImageTopic = Annotated[
    str | None, typer.Option("--image-topic", metavar="T", help="Colour Image or CompressedImage topic.")
]
DetectionsTopic = Annotated[
    str | None,
    typer.Option(
        "--detections-topic", metavar="T", help="vision_msgs/Detection2DArray topic (robot's detector)."
    ),
]
DepthTopic = Annotated[
    str | None, typer.Option("--depth-topic", metavar="T", help="Aligned depth Image (16UC1 mm or 32FC1 m).")
]
CameraInfoTopic = Annotated[
    str | None, typer.Option("--camera-info-topic", metavar="T", help="sensor_msgs/CameraInfo topic.")
]
OdomTopic = Annotated[
    str | None,
    typer.Option("--odom-topic", metavar="T", help="nav_msgs/Odometry topic [default: /tf odom->base]."),
]
ScanTopic = Annotated[
    str | None, typer.Option("--scan-topic", metavar="T", help="sensor_msgs/LaserScan topic.")
]
PoseTopic = Annotated[
    str | None,
    typer.Option(
        "--pose-topic",
        metavar="T|tf",
        help="The localiser's PoseWithCovarianceStamped [default: /amcl_pose where the bag has it];"
        " tf: map -> odom on /tf.",
    ),
]
BaseFrame = Annotated[
    str | None,
    typer.Option("--base-frame", metavar="F", help="Robot base frame [default: the odometry's child]."),
]
Model = Annotated[
    str, typer.Option("--model", metavar="default|M.onnx", help="ONNX detector for colour images.")
]
Rate = Annotated[
    float | None,
    typer.Option(
        "--rate",
        metavar="HZ",
        help="Use at most this many images per second, (0, 1000].",
        callback=number_option("bim-init", above=0, maximum=1000),
    ),
]
ClassNames = Annotated[
    str | None,
    typer.Option(
        "--class-names", metavar="door,lift,stairs", help="Names of numeric class ids (0,1,2.. or 0=door,..)."
    ),
]


def bag_options(
    image_topic: str | None = None,
    detections_topic: str | None = None,
    depth_topic: str | None = None,
    camera_info_topic: str | None = None,
    odom_topic: str | None = None,
    scan_topic: str | None = None,
    base_frame: str | None = None,
    model: str = "default",
    rate: float | None = None,
    class_names: str | None = None,
) -> Bag2LogOptions:
    """The options as the reader takes them (``--class-names`` parsed: InputError when malformed)."""
    from initcli.ros.bag_reader import parse_class_names

    return Bag2LogOptions(
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
