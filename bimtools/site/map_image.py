"""The image of an occupancy map, decoded and checked against its own header.

PGM (``P5`` binary and ``P2`` plain, 8 or 16 bit) is read here, so that a header that disagrees
with its data (a width, height or maxval that does not fit the pixels) is refused by name instead
of read sheared; every other format (PNG, BMP, PPM...) goes through OpenCV, a PNG's size checked
from its IHDR before it is decoded (a small file cannot unpack into a huge image).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bimkit.checks import read_bytes
from bimkit.errors import InputError
from bimkit.limits import MAX_MAP_BYTES

__all__ = ["MAX_MAP_CELLS", "MapImage", "decode_map_image", "read_map_image"]

MAX_MAP_CELLS = 200_000_000  # pixels of one map image (10 km x 10 km at 0.7 m, 700 m x 700 m at 5 cm)
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class MapImage:
    """``gray``: the grey level of each pixel (float, the mean of the colour channels), row 0 the
    top; ``maxval``: the level of white; ``opaque``: False where an alpha channel is not opaque
    (None: no alpha)."""

    gray: np.ndarray
    maxval: int
    opaque: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        rows, cols = self.gray.shape
        return int(rows), int(cols)


def _check_size(path: Path, cols: int, rows: int, kind: str = "image") -> None:
    if cols < 1 or rows < 1:
        raise InputError(f"{path}: {kind} of {cols} x {rows} pixels: expected at least 1 x 1")
    if cols * rows > MAX_MAP_CELLS:
        raise InputError(
            f"{path}: {kind} of {cols} x {rows} pixels is over the limit of {MAX_MAP_CELLS} pixels"
        )


def _pgm_header(path: Path, data: bytes) -> tuple[bytes, int, int, int, int]:
    """(magic, width, height, maxval, offset of the first pixel byte)."""
    tokens: list[bytes] = []
    pos = 0
    while len(tokens) < 4:
        while pos < len(data) and data[pos : pos + 1].isspace():
            pos += 1
        if data[pos : pos + 1] == b"#":
            while pos < len(data) and data[pos : pos + 1] not in (b"\n", b"\r"):
                pos += 1
            continue
        start = pos
        while pos < len(data) and not data[pos : pos + 1].isspace() and data[pos : pos + 1] != b"#":
            pos += 1
        if start == pos:
            raise InputError(f"{path}: truncated PGM header")
        tokens.append(data[start:pos])
    if not all(t.isdigit() and len(t) <= 9 for t in tokens[1:]):
        shown = b" ".join(tokens).decode("latin-1")
        raise InputError(
            f"{path}: PGM header {shown!r}: expected {tokens[0].decode('latin-1')} width height maxval"
        )
    cols, rows, maxval = int(tokens[1]), int(tokens[2]), int(tokens[3])
    _check_size(path, cols, rows, "PGM")
    if not 1 <= maxval <= 65535:
        raise InputError(f"{path}: PGM maxval {maxval}: expected 1 to 65535")
    if pos >= len(data) or not data[pos : pos + 1].isspace():
        raise InputError(f"{path}: truncated PGM header (no pixels after the maxval)")
    return tokens[0], cols, rows, maxval, pos + 1


def _read_pgm(path: Path, data: bytes) -> MapImage:
    magic, cols, rows, maxval, offset = _pgm_header(path, data)
    count = rows * cols
    if magic == b"P5":
        width = 1 if maxval < 256 else 2
        body = data[offset:]
        if len(body) < count * width:
            raise InputError(
                f"{path}: PGM has {len(body) // width} of {count} pixels (truncated; its header says "
                f"{cols} x {rows})"
            )
        if len(body) > count * width:
            raise InputError(
                f"{path}: PGM header disagrees with its data: {cols} x {rows} pixels of {width} byte(s) "
                f"is {count * width} bytes, the file holds {len(body)}"
            )
        pixels = np.frombuffer(body, dtype=np.uint8 if width == 1 else ">u2").reshape(rows, cols)
    else:  # P2: plain (ASCII) PGM
        lines = [line.split(b"#", 1)[0] for line in data[offset:].splitlines()]
        words = b" ".join(lines).split()
        if not all(w.isdigit() and len(w) <= 5 for w in words):
            bad = next(w for w in words if not (w.isdigit() and len(w) <= 5))
            raise InputError(
                f"{path}: plain PGM pixel {bad[:20].decode('latin-1')!r}: expected a whole number"
            )
        if len(words) != count:
            raise InputError(
                f"{path}: PGM header disagrees with its data: {cols} x {rows} is {count} pixels, the file "
                f"holds {len(words)}" + (" (truncated)" if len(words) < count else "")
            )
        pixels = np.array([int(w) for w in words], dtype=np.int64).reshape(rows, cols)
    top = int(pixels.max())
    if top > maxval:
        raise InputError(
            f"{path}: PGM header disagrees with its data: a pixel of {top} above the maxval {maxval}"
        )
    return MapImage(pixels.astype(np.float64), maxval)


def _png_size(path: Path, data: bytes) -> None:
    if len(data) < 24 or data[12:16] != b"IHDR":
        raise InputError(f"{path}: truncated PNG (no IHDR header)")
    cols, rows = struct.unpack(">II", data[16:24])
    _check_size(path, cols, rows, "PNG")


def _read_other(path: Path, data: bytes) -> MapImage:
    import cv2

    if data.startswith(_PNG_MAGIC):
        _png_size(path, data)
    try:
        image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    except cv2.error:
        image = None
    if image is None:
        raise InputError(f"{path}: not a map image (expected a PGM, or a PNG or another image OpenCV reads)")
    if image.ndim == 2:
        _check_size(path, image.shape[1], image.shape[0])
        channels = image[:, :, None]
    else:
        channels = image
        _check_size(path, image.shape[1], image.shape[0])
    if data.startswith(_PNG_MAGIC):
        cols, rows = struct.unpack(">II", data[16:24])
        if (rows, cols) != image.shape[:2]:
            raise InputError(
                f"{path}: PNG header disagrees with its data: {cols} x {rows} pixels in the header, "
                f"{image.shape[1]} x {image.shape[0]} decoded"
            )
    if image.dtype == np.uint8:
        maxval = 255
    elif image.dtype == np.uint16:
        maxval = 65535
    else:
        raise InputError(f"{path}: {image.dtype} pixels: expected an 8 or 16 bit image")
    count = channels.shape[2]
    opaque = None
    if count in (2, 4):  # grey + alpha, BGRA
        opaque = channels[:, :, -1] == maxval
        channels = channels[:, :, :-1]
    gray = channels.astype(np.float64).mean(axis=2)
    return MapImage(gray, maxval, opaque)


def decode_map_image(path: Path, data: bytes) -> MapImage:
    """The pixels of ``data`` (the bytes of ``path``, named in messages)."""
    path = Path(path)
    if data[:2] in (b"P5", b"P2") and (len(data) < 3 or data[2:3].isspace() or data[2:3] == b"#"):
        return _read_pgm(path, data)
    return _read_other(path, data)


def read_map_image(path: Path) -> MapImage:
    """The map image at ``path`` (at most MAX_MAP_BYTES), checked against its header."""
    return decode_map_image(path, read_bytes(Path(path), "a map image (PGM or PNG)", MAX_MAP_BYTES))
