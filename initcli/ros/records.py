"""Typed records of the ROS link: the topics chosen in a bag, transforms, the pose sent to Nav2."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from initcli.config.watch import AMCL_POSE_TOPIC, POSE_FROM_TF
from initcli.detector import DETECTOR_CONFIDENCE

__all__ = [
    "AMCL_POSE_TOPIC",
    "DIAGNOSTICS_TOPIC",
    "DIAGNOSTIC_ARRAY",
    "POSE_FROM_TF",
    "Bag2LogOptions",
    "Bag2LogStats",
    "BagTopics",
    "CAMERA_INFO",
    "CMD_VEL_TOPIC",
    "COMPRESSED_IMAGE",
    "DEPTH_ENCODINGS",
    "DETECTION_2D_ARRAY",
    "HYPOTHESES_TOPIC",
    "IMAGE",
    "INITIALPOSE_TOPIC",
    "InitialPose",
    "LASER_SCAN",
    "MAP_TOPIC",
    "OCCUPANCY_GRID",
    "ODOMETRY",
    "POSE_ARRAY",
    "POSE_WITH_COVARIANCE_STAMPED",
    "STATE_TOPIC",
    "STRING",
    "TF_MESSAGE",
    "TWIST",
    "Topic",
    "Transform",
]

# Message types, ROS 2 spelling (rosbags names ROS 1 types the same way).
IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
ODOMETRY = "nav_msgs/msg/Odometry"
OCCUPANCY_GRID = "nav_msgs/msg/OccupancyGrid"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
DETECTION_2D_ARRAY = "vision_msgs/msg/Detection2DArray"
POSE_WITH_COVARIANCE_STAMPED = "geometry_msgs/msg/PoseWithCovarianceStamped"
POSE_ARRAY = "geometry_msgs/msg/PoseArray"
TWIST = "geometry_msgs/msg/Twist"
STRING = "std_msgs/msg/String"

DEPTH_ENCODINGS = ("16UC1", "32FC1", "mono16")  # 16UC1 / mono16: millimetres; 32FC1: metres

# Topic names bim-init writes and publishes.
INITIALPOSE_TOPIC = "/initialpose"
DIAGNOSTICS_TOPIC = "/diagnostics"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"

HYPOTHESES_TOPIC = "/bim_init/hypotheses"
STATE_TOPIC = "/bim_init/state"
MAP_TOPIC = "/map"
CMD_VEL_TOPIC = "/cmd_vel"


@dataclass(frozen=True)
class Topic:
    name: str
    msgtype: str
    count: int = 0

    def describe(self) -> str:
        return f"{self.name} ({self.msgtype}, {self.count} messages)"


@dataclass(frozen=True)
class BagTopics:
    """The topics of a bag that ``bag2log`` reads (no perception, depth and camera info: a bag
    without a camera, read for its scans and odometry)."""

    perception: Topic | None  # Image, CompressedImage or Detection2DArray
    depth: Topic | None
    camera_info: Topic | None
    odom: Topic | None  # nav_msgs/Odometry; None: odometry from /tf
    tf: Topic | None
    tf_static: Topic | None
    scan: Topic | None
    # the localiser's pose (geometry_msgs/PoseWithCovarianceStamped, /amcl_pose by default; None:
    # not read, or from /tf map -> odom when Bag2LogOptions.pose_topic is "tf")
    localiser: Topic | None = None

    @property
    def camera_absent(self) -> bool:
        return self.perception is None

    @property
    def perception_kind(self) -> str:
        assert self.perception is not None
        return {IMAGE: "image", COMPRESSED_IMAGE: "compressed", DETECTION_2D_ARRAY: "detections"}[
            self.perception.msgtype
        ]


@dataclass(frozen=True)
class Transform:
    """``parent -> child``: the child frame's pose in the parent (rotation matrix, translation m)."""

    parent: str
    child: str
    rotation: np.ndarray = field(compare=False)
    translation: np.ndarray = field(compare=False)


@dataclass(frozen=True)
class Bag2LogOptions:
    image_topic: str | None = None
    detections_topic: str | None = None
    depth_topic: str | None = None
    camera_info_topic: str | None = None
    odom_topic: str | None = None
    scan_topic: str | None = None
    # the localiser's pose: a PoseWithCovarianceStamped topic, or "tf" (map -> odom on /tf); None:
    # /amcl_pose when the bag has it
    pose_topic: str | None = None
    lidar_only: bool = False  # the camera left unread (bim-init watch): scans, odometry, the localiser
    base_frame: str | None = None  # None: the odometry's child frame
    model: str | Path = "default"
    rate: float | None = None  # Hz: images used at most this often; None: every image
    class_names: tuple[str, ...] | dict[str, str] | None = None  # numeric class ids -> names
    depth_window: int = 2  # n: (2n+1)^2 window of Eq. 1
    score_threshold: float = DETECTOR_CONFIDENCE  # the detector's confidence (the match filters again)
    threads: int = 2


@dataclass
class Bag2LogStats:
    messages: int = 0
    images: int = 0  # perception messages turned into detections records
    objects: int = 0
    objects_without_depth: int = 0
    odom: int = 0
    scans: int = 0
    localiser: int = 0  # the localiser's poses (localiser records)
    without_depth: int = 0
    outside_odometry: int = 0
    skipped_rate: int = 0
    seconds: float = 0.0
    camera_absent: bool = False  # no camera in the input: the log has scans and odometry only
    warnings: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class InitialPose:
    """``geometry_msgs/PoseWithCovarianceStamped`` for Nav2/AMCL's ``/initialpose``.

    ``covariance`` is the row-major 6x6 of (x, y, z, roll, pitch, yaw); AMCL reads [0], [7], [35].
    """

    stamp: float  # s: the time of the image the pose rests on
    x: float
    y: float
    yaw: float
    covariance: tuple[float, ...]
    frame_id: str = "map"
