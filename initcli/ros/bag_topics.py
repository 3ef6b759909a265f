"""The topics of a bag that ``bag2log`` reads: chosen by message type when the bag holds exactly one
of a kind (colour and depth images told apart by their encoding), otherwise by the options; an
:class:`InputError` naming the candidates when the choice is not clear. A bag without a camera (no
colour image, compressed image or Detection2DArray) is read for its laser scan and odometry."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace
from typing import TYPE_CHECKING

from bimkit.errors import InputError
from initcli.ros.records import (
    AMCL_POSE_TOPIC,
    CAMERA_INFO,
    COMPRESSED_IMAGE,
    DEPTH_ENCODINGS,
    DETECTION_2D_ARRAY,
    IMAGE,
    LASER_SCAN,
    ODOMETRY,
    POSE_FROM_TF,
    POSE_WITH_COVARIANCE_STAMPED,
    TF_MESSAGE,
    Bag2LogOptions,
    BagTopics,
    Topic,
)

if TYPE_CHECKING:
    from initcli.ros.bag_source import BagSource

__all__ = ["choose_topics"]


def _listing(topics: Iterable[Topic]) -> str:
    return "; ".join(t.describe() for t in topics) or "none"


def _pick(
    source: BagSource, given: str | None, types: tuple[str, ...], what: str, flag: str, required: bool
) -> Topic | None:
    if given is not None:
        topic = source.topics.get(given)
        if topic is None:
            raise InputError(
                f"{source.path}: no topic {given} ({flag}); the bag has: {_listing(source.topics.values())}"
            )
        if topic.msgtype not in types:
            raise InputError(f"{given} is {topic.msgtype}, {flag} needs {' or '.join(types)}")
        return topic
    found = [t for t in source.topics.values() if t.msgtype in types]
    if len(found) == 1:
        return found[0]
    if not found:
        if required:
            raise InputError(
                f"{source.path}: no {what} topic ({' or '.join(types)}); the bag has: "
                f"{_listing(source.topics.values())}"
            )
        return None
    raise InputError(f"{source.path}: several {what} topics, choose one with {flag}: {_listing(found)}")


def _encoding(source: BagSource, topic: Topic) -> str:
    msg = source.first(topic.name)
    return str(getattr(msg, "encoding", "")) if msg is not None else ""


def choose_topics(source: BagSource, options: Bag2LogOptions) -> BagTopics:
    """The topics to read; InputError naming the candidates when the choice is not clear."""
    topics = _sensor_topics(source, options)
    return replace(topics, localiser=_localiser_topic(source, options))


def _localiser_topic(source: BagSource, options: Bag2LogOptions) -> Topic | None:
    """``--pose-topic`` (a PoseWithCovarianceStamped; ``tf``: /tf map -> odom, read with the
    transforms), else /amcl_pose when the bag has it as one, else None."""
    if options.pose_topic == POSE_FROM_TF:
        if source.topics.get("/tf", Topic("", "")).msgtype != TF_MESSAGE:
            raise InputError(f"{source.path}: --pose-topic tf, but the bag has no /tf")
        return None
    if options.pose_topic is not None:
        kinds = (POSE_WITH_COVARIANCE_STAMPED,)
        return _pick(source, options.pose_topic, kinds, "localiser pose", "--pose-topic", True)
    amcl = source.topics.get(AMCL_POSE_TOPIC)
    return amcl if amcl is not None and amcl.msgtype == POSE_WITH_COVARIANCE_STAMPED else None


def _sensor_topics(source: BagSource, options: Bag2LogOptions) -> BagTopics:
    if options.image_topic and options.detections_topic:
        raise InputError("give --image-topic or --detections-topic, not both")
    if options.lidar_only:
        return _lidar_topics(source, options)
    images = [t for t in source.topics.values() if t.msgtype == IMAGE]
    encodings = {t.name: _encoding(source, t) for t in images}
    if _camera_absent(source, options, images, encodings):
        return _lidar_topics(source, options)
    depth = _depth_topic(source, options, images, encodings)
    colour_like = [t for t in images if encodings[t.name] not in DEPTH_ENCODINGS]
    perception = _perception_topic(source, options, [t for t in colour_like if t.name != depth.name])
    if perception.name == depth.name:
        raise InputError(f"{depth.name} is the depth image; the colour image must be another topic")

    camera_info = _pick(
        source, options.camera_info_topic, (CAMERA_INFO,), "camera info", "--camera-info-topic", False
    )
    if camera_info is None:
        raise InputError(
            f"{source.path}: no sensor_msgs/CameraInfo topic: the camera intrinsics are needed "
            f"(the bag has: {_listing(source.topics.values())})"
        )
    scan = _pick(source, options.scan_topic, (LASER_SCAN,), "laser scan", "--scan-topic", False)
    return BagTopics(perception, depth, camera_info, *_odometry_topics(source, options), scan)


def _odometry_topics(
    source: BagSource, options: Bag2LogOptions
) -> tuple[Topic | None, Topic | None, Topic | None]:
    """The odometry topic (None: /tf odom -> base), /tf and /tf_static."""
    odom = _pick(source, options.odom_topic, (ODOMETRY,), "odometry", "--odom-topic", False)
    tf = source.topics.get("/tf") if source.topics.get("/tf", Topic("", "")).msgtype == TF_MESSAGE else None
    tf_static = (
        source.topics.get("/tf_static")
        if source.topics.get("/tf_static", Topic("", "")).msgtype == TF_MESSAGE
        else None
    )
    if odom is None and tf is None:
        raise InputError(f"{source.path}: no odometry: neither nav_msgs/Odometry nor /tf in the bag")
    return odom, tf, tf_static


def _camera_absent(
    source: BagSource, options: Bag2LogOptions, images: list[Topic], encodings: dict[str, str]
) -> bool:
    """No camera: no colour image, compressed image or Detection2DArray in the bag, and none named."""
    if options.image_topic or options.detections_topic:
        return False
    colour = [t for t in images if encodings[t.name] not in DEPTH_ENCODINGS]
    others = [t for t in source.topics.values() if t.msgtype in (COMPRESSED_IMAGE, DETECTION_2D_ARRAY)]
    return not colour and not others


def _lidar_topics(source: BagSource, options: Bag2LogOptions) -> BagTopics:
    """A bag without a camera: its laser scan and odometry (InputError when it has no scan either)."""
    scan = _pick(source, options.scan_topic, (LASER_SCAN,), "laser scan", "--scan-topic", False)
    if scan is None:
        raise InputError(
            f"{source.path}: neither a camera (colour image or vision_msgs/Detection2DArray) nor a "
            f"sensor_msgs/LaserScan; the bag has: {_listing(source.topics.values())}"
        )
    return BagTopics(None, None, None, *_odometry_topics(source, options), scan)


def _depth_topic(
    source: BagSource, options: Bag2LogOptions, images: list[Topic], encodings: dict[str, str]
) -> Topic:
    """The aligned depth image: ``--depth-topic``, else the one image topic with a depth encoding."""
    depth_like = [t for t in images if encodings[t.name] in DEPTH_ENCODINGS]
    if options.depth_topic is not None:
        depth = _pick(source, options.depth_topic, (IMAGE,), "depth image", "--depth-topic", True)
    elif len(depth_like) == 1:
        depth = depth_like[0]
    elif not depth_like:
        raise InputError(
            f"{source.path}: no aligned depth image (sensor_msgs/Image, 16UC1 or 32FC1); the bag has: "
            f"{_listing(source.topics.values())}"
        )
    else:
        raise InputError(
            f"{source.path}: several depth images, choose one with --depth-topic: "
            + "; ".join(f"{t.describe()} {encodings[t.name]}" for t in depth_like)
        )
    assert depth is not None
    return depth


def _perception_topic(source: BagSource, options: Bag2LogOptions, colour: list[Topic]) -> Topic:
    """What the detections come from: ``--detections-topic`` or ``--image-topic``, else the one
    Detection2DArray topic, else the one colour image (``colour``: raw colour images but the depth)."""
    if options.detections_topic is not None:
        perception = _pick(
            source, options.detections_topic, (DETECTION_2D_ARRAY,), "", "--detections-topic", True
        )
    elif options.image_topic is not None:
        perception = _pick(source, options.image_topic, (IMAGE, COMPRESSED_IMAGE), "", "--image-topic", True)
    else:
        perception = _only_perception_topic(source, colour)
    assert perception is not None
    return perception


def _only_perception_topic(source: BagSource, colour: list[Topic]) -> Topic:
    detections = [t for t in source.topics.values() if t.msgtype == DETECTION_2D_ARRAY]
    compressed = [t for t in source.topics.values() if t.msgtype == COMPRESSED_IMAGE]
    if len(detections) == 1:
        return detections[0]
    if detections:
        raise InputError(
            f"{source.path}: several detection topics, choose one with --detections-topic: "
            f"{_listing(detections)}"
        )
    if len(colour) + len(compressed) == 1:
        return (colour + compressed)[0]
    if not colour and not compressed:
        raise InputError(
            f"{source.path}: no colour image or vision_msgs/Detection2DArray topic; the bag has: "
            f"{_listing(source.topics.values())}"
        )
    listed = "; ".join(f"{t.describe()}" for t in colour + compressed)
    raise InputError(f"{source.path}: several colour image topics, choose one with --image-topic: {listed}")
