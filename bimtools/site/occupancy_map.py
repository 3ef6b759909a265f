"""Occupancy grids in the ROS ``map_server`` / Nav2 format (``map_<storey>.pgm`` + ``.yaml``).

Pixel values: 0 occupied, 254 free, 205 unknown; image row 0 is the top of the map and
``origin`` is the world pose of the lower-left pixel's lower-left corner.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from bimkit.checks import check_number, read_bytes, read_yaml
from bimkit.errors import InputError
from bimkit.limits import MAX_MAP_BYTES
from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "OccupancyGrid", "read_map", "write_map"]


def _pgm_bytes(cells: np.ndarray) -> bytes:
    rows, cols = cells.shape
    return f"P5\n{cols} {rows}\n255\n".encode("ascii") + np.ascontiguousarray(cells, dtype=np.uint8).tobytes()


def write_map(yaml_path: Path, grid: OccupancyGrid) -> None:
    """Write ``<stem>.pgm`` beside ``yaml_path`` and the YAML that points to it."""
    yaml_path = Path(yaml_path)
    image = yaml_path.with_suffix(".pgm")
    image.write_bytes(_pgm_bytes(grid.cells))
    meta = {
        "image": image.name,
        "mode": "trinary",
        "resolution": float(grid.resolution),
        "origin": [round(float(v), 6) for v in grid.origin],
        "negate": int(grid.negate),
        "occupied_thresh": float(grid.occupied_thresh),
        "free_thresh": float(grid.free_thresh),
    }
    yaml_path.write_text(yaml.safe_dump(meta, sort_keys=False), encoding="utf-8")


def _read_pgm(path: Path) -> np.ndarray:
    data = read_bytes(path, "a map image (PGM)", MAX_MAP_BYTES)
    tokens: list[bytes] = []
    pos = 0
    while len(tokens) < 4:
        while pos < len(data) and data[pos : pos + 1].isspace():
            pos += 1
        if data[pos : pos + 1] == b"#":
            while pos < len(data) and data[pos : pos + 1] != b"\n":
                pos += 1
            continue
        start = pos
        while pos < len(data) and not data[pos : pos + 1].isspace():
            pos += 1
        if start == pos:
            raise InputError(f"{path}: truncated PGM header")
        tokens.append(data[start:pos])
    if tokens[0] != b"P5":
        raise InputError(f"{path}: not a binary PGM (P5) image")
    if not all(t.isdigit() and len(t) <= 9 for t in tokens[1:]):
        raise InputError(
            f"{path}: PGM header {b' '.join(tokens).decode('latin-1')!r}: expected P5 width height 255"
        )
    cols, rows, maxval = int(tokens[1]), int(tokens[2]), int(tokens[3])
    if cols < 1 or rows < 1 or maxval < 1:
        raise InputError(f"{path}: PGM of {cols} x {rows} pixels (maxval {maxval}): expected at least 1 x 1")
    if maxval > 255:
        raise InputError(f"{path}: 16-bit PGM is not supported")
    body = data[pos + 1 : pos + 1 + rows * cols]
    if len(body) != rows * cols:
        raise InputError(f"{path}: PGM has {len(body)} of {rows * cols} pixels (truncated)")
    return np.frombuffer(body, dtype=np.uint8).reshape(rows, cols).copy()


MAX_ORIGIN = 1e6  # m: the map's origin (a building is far smaller)


def read_map(yaml_path: Path) -> OccupancyGrid:
    """A map YAML and its PGM, checked as ``map.schema.json`` describes them: a positive resolution,
    a finite origin [x, y, yaw], negate 0 or 1, thresholds in [0, 1] (one line naming the key)."""
    yaml_path = Path(yaml_path)
    meta = read_yaml(yaml_path, "a map YAML (ROS map_server)")
    for key in ("image", "resolution", "origin"):
        if not isinstance(meta, dict) or key not in meta:
            raise InputError(f"{yaml_path}: missing key {key!r}")
    if not isinstance(meta["image"], str) or not meta["image"].strip():
        raise InputError(f"{yaml_path}: image: expected a file name, got {meta['image']!r}")
    origin = meta["origin"]
    if not isinstance(origin, list) or len(origin) != 3:
        raise InputError(f"{yaml_path}: origin: expected [x, y, yaw], got {origin!r}")
    resolution = check_number(meta["resolution"], f"{yaml_path}: resolution", above=0, maximum=100)
    for k, v in enumerate(origin):
        check_number(v, f"{yaml_path}: origin.{k}", minimum=-MAX_ORIGIN, maximum=MAX_ORIGIN)
    negate = meta.get("negate", 0)
    if negate not in (0, 1) or isinstance(negate, bool):
        raise InputError(f"{yaml_path}: negate: expected 0 or 1, got {negate!r}")
    thresholds = {k: meta.get(k, d) for k, d in (("occupied_thresh", 0.65), ("free_thresh", 0.196))}
    for key, value in thresholds.items():
        check_number(value, f"{yaml_path}: {key}", minimum=0, maximum=1)
    image = yaml_path.parent / meta["image"]
    name = (
        meta["image"]
        if len(meta["image"]) <= 80
        else f"{meta['image'][:60]}... ({len(meta['image'])} characters)"
    )
    try:
        found = image.exists()
    except OSError as exc:  # a name too long for the file system, say: Path.exists raises those
        raise InputError(f"{yaml_path}: image {name!r}: {exc.strerror or exc}") from None
    if not found:
        raise InputError(f"{yaml_path}: image {name!r} not found")
    return OccupancyGrid(
        cells=_read_pgm(image),
        resolution=float(resolution),
        origin=tuple(float(v) for v in origin),  # type: ignore[arg-type]
        negate=int(negate),
        occupied_thresh=float(thresholds["occupied_thresh"]),
        free_thresh=float(thresholds["free_thresh"]),
    )
