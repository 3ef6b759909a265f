"""The stated limits on what a command reads, written once (each reader names the one it uses).

A file over its limit, a document nested deeper, an integer with more digits or a YAML document
whose aliases would expand past the budget is refused with one line (exit code 2) before it is
read whole: a hostile or broken input never exhausts memory or time.
"""

from __future__ import annotations

MiB = 1 << 20
GiB = 1 << 30

MAX_TEXT_BYTES = 64 * MiB  # a config, a categories file, features.csv, walls.geojson, a summary, a manifest
MAX_LOG_BYTES = 1 * GiB  # a detection log (about 10 hours of a session with a lidar)
MAX_LOG_LINE_BYTES = 16 * MiB  # one record of a detection log
MAX_IFC_BYTES = 2 * GiB  # an IFC model
MAX_MAP_BYTES = 1 * GiB  # an occupancy map's PGM image
MAX_IMAGE_BYTES = 256 * MiB  # a photo for the detector
MAX_MODEL_BYTES = 2 * GiB  # a detector checkpoint or ONNX model
MAX_BAG_BYTES = 1024 * GiB  # a ROS bag file (read message by message, never whole)

MAX_DEPTH = 64  # levels of nesting in a JSON or YAML document
MAX_INT_DIGITS = 40  # digits of an integer in a JSON or YAML document (2**64 has 20)
MAX_YAML_ALIAS_NODES = 10_000  # nodes the aliases of a YAML document may add to it when expanded

__all__ = [
    "GiB",
    "MAX_BAG_BYTES",
    "MAX_DEPTH",
    "MAX_IFC_BYTES",
    "MAX_IMAGE_BYTES",
    "MAX_INT_DIGITS",
    "MAX_LOG_BYTES",
    "MAX_LOG_LINE_BYTES",
    "MAX_MAP_BYTES",
    "MAX_MODEL_BYTES",
    "MAX_TEXT_BYTES",
    "MAX_YAML_ALIAS_NODES",
    "MiB",
    "show_bytes",
]


def show_bytes(n: int) -> str:
    """``2 GiB``, ``64 MiB``, ``512 bytes``."""
    for unit, size in (("GiB", GiB), ("MiB", MiB), ("KiB", 1024)):
        if n >= size:
            value = n / size
            return f"{value:.0f} {unit}" if value == int(value) else f"{value:.1f} {unit}"
    return f"{n} bytes"
