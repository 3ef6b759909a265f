"""Occupancy grids in the ROS ``map_server`` / Nav2 format (``map_<storey>.pgm`` + ``.yaml``).

Pixel values: 0 occupied, 254 free, 205 unknown; image row 0 is the top of the map and
``origin`` is the world pose of the lower-left pixel's lower-left corner.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from bimkit.checks import read_yaml
from bimkit.errors import InputError
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
    data = path.read_bytes()
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
    cols, rows, maxval = int(tokens[1]), int(tokens[2]), int(tokens[3])
    if maxval > 255:
        raise InputError(f"{path}: 16-bit PGM is not supported")
    body = data[pos + 1 : pos + 1 + rows * cols]
    if len(body) != rows * cols:
        raise InputError(f"{path}: PGM has {len(body)} of {rows * cols} pixels (truncated)")
    return np.frombuffer(body, dtype=np.uint8).reshape(rows, cols).copy()


def read_map(yaml_path: Path) -> OccupancyGrid:
    yaml_path = Path(yaml_path)
    meta = read_yaml(yaml_path, "a map YAML (ROS map_server)")
    for key in ("image", "resolution", "origin"):
        if not isinstance(meta, dict) or key not in meta:
            raise InputError(f"{yaml_path}: missing key {key!r}")
    image = yaml_path.parent / str(meta["image"])
    if not image.exists():
        raise InputError(f"{yaml_path}: image {meta['image']!r} not found")
    return OccupancyGrid(
        cells=_read_pgm(image),
        resolution=float(meta["resolution"]),
        origin=tuple(float(v) for v in meta["origin"]),  # type: ignore[arg-type]
        negate=int(meta.get("negate", 0)),
        occupied_thresh=float(meta.get("occupied_thresh", 0.65)),
        free_thresh=float(meta.get("free_thresh", 0.196)),
    )
