"""Occupancy grids in the ROS ``map_server`` / Nav2 format (``map_<storey>.pgm`` + ``.yaml``).

Pixel values: 0 occupied, 254 free, 205 unknown; image row 0 is the top of the map and
``origin`` is the world pose of the lower-left pixel's lower-left corner.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from bimkit.checks import check_number, read_yaml
from bimkit.errors import InputError
from bimtools.site.map_image import MapImage, read_map_image
from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid

__all__ = [
    "FREE",
    "MODES",
    "OCCUPIED",
    "UNKNOWN",
    "OccupancyGrid",
    "classify",
    "map_image_path",
    "read_map",
    "write_map",
]


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


MAX_ORIGIN = 1e6  # m: the map's origin (a building is far smaller)
RESOLUTION_LIMITS = (0.001, 100.0)  # m per pixel: a millimetre to a hundred metres
MODES = ("trinary", "scale", "raw")


def map_image_path(yaml_path: Path) -> Path | None:
    """The image a map YAML names (None when the YAML does not name one): for the list of inputs
    a command checks its outputs against, before the map is read."""
    try:
        meta = read_yaml(Path(yaml_path), "a map YAML (ROS map_server)")
    except InputError:
        return None
    image = meta.get("image") if isinstance(meta, dict) else None
    if not isinstance(image, str) or not image.strip() or len(image) > 4096:
        return None
    return Path(yaml_path).parent / image


def classify(
    image: MapImage,
    mode: str = "trinary",
    negate: int = 0,
    occupied_thresh: float = 0.65,
    free_thresh: float = 0.196,
) -> np.ndarray:
    """The trinary cells (OCCUPIED, FREE, UNKNOWN) of a map image as map_server / Nav2 load it.

    trinary: p = (maxval - v) / maxval (v / maxval with ``negate``); p > occupied_thresh occupied,
    p < free_thresh free, else unknown. scale: the same, and a pixel whose alpha is not opaque is
    unknown; the in-between values Nav2 keeps as 1..99 stay unknown here (a site's map is trinary).
    raw: the value is the occupancy in percent (0..100, scaled to 8 bit as Nav2 does), thresholded
    the same way; any other value (255, -1) is unknown; ``negate`` does not apply.
    """
    gray, top = image.gray, float(image.maxval)
    if mode == "raw":
        value = np.rint(gray * (255.0 / top)) if image.maxval != 255 else gray
        known = value <= 100
        p = value / 100.0
    else:
        known = np.ones(gray.shape, dtype=bool)
        p = gray / top if negate else (top - gray) / top
        if mode == "scale" and image.opaque is not None:
            known &= image.opaque
    cells = np.full(gray.shape, UNKNOWN, dtype=np.uint8)
    cells[known & (p > occupied_thresh)] = OCCUPIED
    cells[known & (p < free_thresh)] = FREE
    return cells


def _thresholds(yaml_path: Path, meta: dict[str, object]) -> dict[str, float]:
    """occupied_thresh and free_thresh (map_server's defaults 0.65 and 0.196), each in [0, 1] and
    free_thresh at most occupied_thresh."""
    thresholds = {k: meta.get(k, d) for k, d in (("occupied_thresh", 0.65), ("free_thresh", 0.196))}
    for key, value in thresholds.items():
        check_number(value, f"{yaml_path}: {key}", minimum=0, maximum=1)  # type: ignore[arg-type]
    checked = {k: float(v) for k, v in thresholds.items()}  # type: ignore[arg-type]
    if checked["free_thresh"] > checked["occupied_thresh"]:
        raise InputError(
            f"{yaml_path}: free_thresh {thresholds['free_thresh']} is above occupied_thresh "
            f"{thresholds['occupied_thresh']}"
        )
    return checked


def read_map(yaml_path: Path) -> OccupancyGrid:
    """A ROS map_server / Nav2 map: the YAML and its image (PGM P5 or P2, PNG or another image OpenCV
    reads), as trinary cells (:func:`classify`; written back by :func:`write_map` it is the same
    map). Checked as ``map.schema.json`` describes it, one line naming the key: a resolution of
    RESOLUTION_LIMITS, a finite origin [x, y, 0] (a yaw is refused: the grid is not rotated), negate
    0 or 1, thresholds in [0, 1] with free_thresh at most occupied_thresh, a mode of MODES, and an
    image that agrees with its header."""
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
    low, high = RESOLUTION_LIMITS
    resolution = check_number(meta["resolution"], f"{yaml_path}: resolution", above=0, maximum=high)
    check_number(resolution, f"{yaml_path}: resolution", minimum=low)
    for k, v in enumerate(origin):
        check_number(v, f"{yaml_path}: origin.{k}", minimum=-MAX_ORIGIN, maximum=MAX_ORIGIN)
    if origin[2] != 0:
        raise InputError(
            f"{yaml_path}: origin yaw {origin[2]!r}: a rotated map is not supported; rotate the image "
            "and set the yaw to 0"
        )
    negate = meta.get("negate", 0)
    if negate not in (0, 1) or isinstance(negate, bool):
        raise InputError(f"{yaml_path}: negate: expected 0 or 1, got {negate!r}")
    mode = meta.get("mode", "trinary")
    if mode not in MODES:
        shown = repr(mode) if len(repr(mode)) <= 40 else f"{repr(mode)[:30]}..."
        raise InputError(f"{yaml_path}: mode: expected one of {', '.join(MODES)}, got {shown}")
    thresholds = _thresholds(yaml_path, meta)
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
    pixels = read_map_image(image)
    rows, cols = pixels.shape
    for k, count in ((0, cols), (1, rows)):
        if abs(float(origin[k]) + count * float(resolution)) > MAX_ORIGIN:
            raise InputError(
                f"{yaml_path}: {cols} x {rows} pixels of {resolution} m from origin {origin!r} reach "
                f"past +-{MAX_ORIGIN:g} m"
            )
    return OccupancyGrid(
        cells=classify(
            pixels,
            str(mode),
            int(negate),
            float(thresholds["occupied_thresh"]),
            float(thresholds["free_thresh"]),
        ),
        resolution=float(resolution),
        origin=(float(origin[0]), float(origin[1]), 0.0),
    )
