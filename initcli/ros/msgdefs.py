"""Message definitions and type registration for reading and writing ROS bags without ROS.

The standard messages (``sensor_msgs``, ``nav_msgs``, ``geometry_msgs``, ``tf2_msgs``, ...) come
with rosbags' ROS 2 Humble typestore. ``vision_msgs`` does not, so its ``.msg`` text is bundled
here in each layout a robot may record (the released packages' definitions):

- ``humble``: vision_msgs 4.x (ROS 2 Humble, Iron, Jazzy): ``ObjectHypothesisWithPose.hypothesis
  .class_id`` and ``BoundingBox2D.center.position.x`` (a ``vision_msgs/Pose2D``); Detection2D ends
  with ``string id``.
- ``galactic``: vision_msgs 3.x (ROS 2 Galactic): as ``humble`` but ``BoundingBox2D.center`` is a
  ``geometry_msgs/Pose2D`` (``center.x``). The same bytes as ``humble``.
- ``foxy``: vision_msgs 2.0.0 (ROS 2 Foxy): ``ObjectHypothesisWithPose.id`` (a string) and
  ``score``; Detection2D ends with ``sensor_msgs/Image source_img``, ``bool is_tracking`` and
  ``string tracking_id``. Other bytes than ``humble``.
- ``noetic``: vision_msgs 0.0.x (ROS 1 Noetic): ``ObjectHypothesisWithPose.id`` is an ``int64``;
  Detection2D ends with ``sensor_msgs/Image source_img``. (A ROS 1 bag carries its definitions.)

A ROS 2 bag without definitions (a Foxy or Humble ``.db3``) is read with the layout its bytes
parse in (:func:`detect_layout`); :func:`detection_fields` and :func:`bbox_centre` read every one.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

__all__ = [
    "CDR_LAYOUTS",
    "MSG_TEXT",
    "VISION_MSGS_LAYOUTS",
    "bbox_centre",
    "detect_layout",
    "detection_fields",
    "from_dict",
    "register_missing",
    "ros1_typestore",
    "ros2_typestore",
    "to_dict",
    "vision_types",
    "with_layout",
]

VISION_MSGS_LAYOUTS = ("humble", "galactic", "foxy", "noetic")
CDR_LAYOUTS = ("humble", "foxy")  # ROS 2 layouts with bytes of their own (galactic's are humble's)

_ARRAY = {
    "vision_msgs/msg/Detection2DArray": "std_msgs/Header header\nvision_msgs/Detection2D[] detections\n"
}
_HYPOTHESIS = {
    "vision_msgs/msg/ObjectHypothesis": "string class_id\nfloat64 score\n",
    "vision_msgs/msg/ObjectHypothesisWithPose": (
        "vision_msgs/ObjectHypothesis hypothesis\ngeometry_msgs/PoseWithCovariance pose\n"
    ),
}
_DETECTION_WITH_ID = {
    "vision_msgs/msg/Detection2D": (
        "std_msgs/Header header\nvision_msgs/ObjectHypothesisWithPose[] results\n"
        "vision_msgs/BoundingBox2D bbox\nstring id\n"
    ),
}
_GEOMETRY_BOX = {
    "vision_msgs/msg/BoundingBox2D": "geometry_msgs/Pose2D center\nfloat64 size_x\nfloat64 size_y\n"
}

_HUMBLE = {
    **_ARRAY,
    **_DETECTION_WITH_ID,
    **_HYPOTHESIS,
    "vision_msgs/msg/Point2D": "float64 x\nfloat64 y\n",
    "vision_msgs/msg/Pose2D": "vision_msgs/Point2D position\nfloat64 theta\n",
    "vision_msgs/msg/BoundingBox2D": "vision_msgs/Pose2D center\nfloat64 size_x\nfloat64 size_y\n",
}

_GALACTIC = {**_ARRAY, **_DETECTION_WITH_ID, **_HYPOTHESIS, **_GEOMETRY_BOX}

_FOXY = {
    **_ARRAY,
    "vision_msgs/msg/Detection2D": (
        "std_msgs/Header header\nvision_msgs/ObjectHypothesisWithPose[] results\n"
        "vision_msgs/BoundingBox2D bbox\nsensor_msgs/Image source_img\nbool is_tracking\n"
        "string tracking_id\n"
    ),
    "vision_msgs/msg/ObjectHypothesisWithPose": (
        "string id\nfloat64 score\ngeometry_msgs/PoseWithCovariance pose\n"
    ),
    **_GEOMETRY_BOX,
}

_NOETIC = {
    **_ARRAY,
    "vision_msgs/msg/Detection2D": (
        "std_msgs/Header header\nvision_msgs/ObjectHypothesisWithPose[] results\n"
        "vision_msgs/BoundingBox2D bbox\nsensor_msgs/Image source_img\n"
    ),
    "vision_msgs/msg/ObjectHypothesisWithPose": (
        "int64 id\nfloat64 score\ngeometry_msgs/PoseWithCovariance pose\n"
    ),
    **_GEOMETRY_BOX,
}

MSG_TEXT: dict[str, dict[str, str]] = {
    "humble": _HUMBLE,
    "galactic": _GALACTIC,
    "foxy": _FOXY,
    "noetic": _NOETIC,
}
_TF_MESSAGE = "geometry_msgs/TransformStamped[] transforms\n"


def vision_types(layout: str = "humble") -> dict[str, Any]:
    """The ``vision_msgs`` field definitions of one layout, ready for ``Typestore.register``."""
    if layout not in MSG_TEXT:
        raise ValueError(f"unknown vision_msgs layout {layout!r}; one of {', '.join(VISION_MSGS_LAYOUTS)}")
    types: dict[str, Any] = {}
    for name, text in MSG_TEXT[layout].items():
        types.update(get_types_from_msg(text, name))
    return types


def ros2_typestore(layout: str = "humble") -> Typestore:
    """rosbags' ROS 2 Humble typestore plus ``vision_msgs`` in the given layout."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(vision_types(layout))
    return store


def ros1_typestore(layout: str = "noetic") -> Typestore:
    """rosbags' ROS 1 Noetic typestore plus ``vision_msgs`` (for writing ROS 1 test bags)."""
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(vision_types(layout))
    if "tf2_msgs/msg/TFMessage" not in store.fielddefs:
        store.register(get_types_from_msg(_TF_MESSAGE, "tf2_msgs/msg/TFMessage"))
    return store


def with_layout(store: Typestore, layout: str) -> Typestore:
    """A copy of ``store`` whose ``vision_msgs`` are those of ``layout`` (the other types kept, the
    standard types a layout needs taken from the Humble typestore where ``store`` lacks them)."""
    fielddefs = dict(get_typestore(Stores.ROS2_HUMBLE).fielddefs)
    fielddefs.update({k: v for k, v in store.fielddefs.items() if not k.startswith("vision_msgs/")})
    fielddefs.update(vision_types(layout))
    out = get_typestore(Stores.EMPTY)
    out.register(fielddefs)
    return out


def detect_layout(raws: Iterable[bytes], msgtype: str, layouts: Iterable[str] = CDR_LAYOUTS) -> str | None:
    """The first of ``layouts`` in which every CDR message of ``raws`` (of a ``vision_msgs`` type)
    parses, to its last byte; None when none does. Messages without a detection parse in all."""
    stores = {layout: ros2_typestore(layout) for layout in layouts}
    alive = list(stores)
    for raw in raws:
        alive = [layout for layout in alive if _parses(stores[layout], raw, msgtype)]
        if not alive:
            return None
    return alive[0]


def _parses(store: Typestore, raw: bytes, msgtype: str) -> bool:
    try:
        store.deserialize_cdr(raw, msgtype)
    except Exception:  # noqa: BLE001 - rosbags raises SerdeError, struct and decoding errors
        return False
    return True


def register_missing(store: Typestore, msgtypes: set[str]) -> list[str]:
    """Register the bundled definitions of the types in ``msgtypes`` that ``store`` lacks.

    Standard types come from the Humble typestore, ``vision_msgs`` from the Humble layout (a bag
    whose bytes are in another layout gets it from :func:`with_layout`). Returns the names registered.
    """
    missing = {t for t in msgtypes if t not in store.fielddefs}
    if not missing:
        return []
    donor = ros2_typestore("humble")
    wanted: dict[str, Any] = {}

    def add(name: str) -> None:
        if name in wanted or name in store.fielddefs or name not in donor.fielddefs:
            return
        wanted[name] = donor.fielddefs[name]
        for _, (kind, detail) in donor.fielddefs[name][1]:
            for sub in _referenced(kind, detail):
                add(sub)

    for name in sorted(missing):
        add(name)
    if wanted:
        store.register(wanted)
    return sorted(wanted)


def _referenced(kind: Any, detail: Any) -> list[str]:
    """Message type names a field refers to (rosbags' Nodetype: 1 base, 2 name, 3 array, 4 sequence)."""
    if int(kind) == 2:
        return [str(detail)]
    if int(kind) in (3, 4):
        inner_kind, inner_detail = detail[0]
        return _referenced(inner_kind, inner_detail)
    return []


def detection_fields(detection: Any) -> list[tuple[str, float]]:
    """(class id, score) of each hypothesis of a ``vision_msgs/Detection2D``, in every layout (a
    Noetic ``int64`` id as its digits)."""
    out = []
    for result in detection.results:
        hyp = getattr(result, "hypothesis", None)
        if hyp is not None:
            out.append((str(hyp.class_id), float(hyp.score)))
        else:
            out.append((str(result.id), float(result.score)))
    return out


def bbox_centre(bbox: Any) -> tuple[float, float]:
    """Centre (u, v) of a ``vision_msgs/BoundingBox2D`` in every layout."""
    centre = bbox.center
    position = getattr(centre, "position", None)
    if position is not None:
        return float(position.x), float(position.y)
    return float(centre.x), float(centre.y)


_DTYPES = {"bool": np.bool_, "byte": np.uint8, "octet": np.uint8, "char": np.uint8}


def _base_value(name: str, value: Any) -> Any:
    if name == "string" or name == "wstring":
        return "" if value is None else str(value)
    if name == "bool":
        return bool(value)
    if name.startswith("float"):
        return 0.0 if value is None else float(value)
    return 0 if value is None else int(value)


_DEFAULTS = {"geometry_msgs/msg/Quaternion": {"w": 1.0}}  # the .msg defaults that are not zero


def from_dict(store: Typestore, msgtype: str, value: dict[str, Any] | None) -> Any:
    """A message object of ``store`` from a nested dict (rosbridge JSON); missing fields default
    (zero, or the definition's default: a quaternion left out is the identity, w = 1).

    Keys are matched case-insensitively, so one dict serves ROS 2 (``k``) and ROS 1 (``K``) spellings.
    """
    value = value or {}
    lower = {**_DEFAULTS.get(msgtype, {}), **{str(k).lower(): v for k, v in value.items()}}
    cls = store.types[msgtype]
    kwargs: dict[str, Any] = {}
    for fname, (kind, detail) in store.fielddefs[msgtype][1]:
        raw = lower.get(fname.lower())
        kwargs[fname] = _field(store, int(kind), detail, raw)
    return cls(**kwargs)


def _field(store: Typestore, kind: int, detail: Any, raw: Any) -> Any:
    if kind == 1:  # base type: (name, string bound)
        return _base_value(detail[0], raw)
    if kind == 2:
        return from_dict(store, str(detail), raw)
    (inner_kind, inner_detail), count = detail
    items = [] if raw is None else raw
    if int(inner_kind) == 1:
        name = inner_detail[0]
        if name in ("string", "wstring"):
            return [str(v) for v in items]
        dtype = _DTYPES.get(name, np.dtype(name) if name not in _DTYPES else None)
        arr = np.asarray(items, dtype=dtype).reshape(-1)
        if kind == 3 and count and len(arr) != count:
            arr = np.resize(arr, count) if len(arr) else np.zeros(count, dtype=dtype)
        return arr
    out = [_field(store, int(inner_kind), inner_detail, v) for v in items]
    if kind == 3 and count:
        out += [_field(store, int(inner_kind), inner_detail, None) for _ in range(count - len(out))]
    return out


def to_dict(msg: Any) -> Any:
    """A message object as rosbridge JSON (``uint8[]`` as base64, as rosbridge sends it)."""
    import base64
    import dataclasses

    if dataclasses.is_dataclass(msg):
        return {
            f.name: to_dict(getattr(msg, f.name)) for f in dataclasses.fields(msg) if f.name != "__msgtype__"
        }
    if isinstance(msg, np.ndarray):
        if msg.dtype == np.uint8:
            return base64.b64encode(msg.tobytes()).decode("ascii")
        return [None if isinstance(v, float) and not math.isfinite(v) else v for v in msg.tolist()]
    if isinstance(msg, list | tuple):
        return [to_dict(v) for v in msg]
    if isinstance(msg, np.generic):
        return msg.item()
    return msg
