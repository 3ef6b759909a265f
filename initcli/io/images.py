"""Photos read for the detector: a regular file within the size limit, decoded by OpenCV, big enough
to be looked at (one :class:`~bimkit.errors.InputError` line otherwise)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from bimkit.cli import native_stderr_silenced
from bimkit.documents import read_bytes
from bimkit.errors import InputError
from bimkit.limits import MAX_IMAGE_BYTES

__all__ = ["MAX_ASPECT", "MIN_SIDE", "read_image"]

MIN_SIDE = 8  # px: a narrower image has nothing a detector could find
MAX_ASPECT = 64  # width / height (either way): past it the letterboxed image is a line


def read_image(path: Path) -> np.ndarray:
    """The BGR image at ``path`` (PNG, JPEG, ... as OpenCV reads them)."""
    path = Path(path)
    data = np.frombuffer(read_bytes(path, "an image", MAX_IMAGE_BYTES), dtype=np.uint8)
    try:
        with native_stderr_silenced():  # libpng and OpenCV print their complaints past Python
            image = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    except cv2.error:
        image = None
    if image is None:
        raise InputError(f"{path}: cannot read image (not a PNG, JPEG or other image OpenCV reads)")
    h, w = image.shape[:2]
    if min(h, w) < MIN_SIDE or max(h, w) > MAX_ASPECT * min(h, w):
        raise InputError(
            f"{path}: a {w}x{h} image; the detector needs at least {MIN_SIDE} pixels a side and at most "
            f"{MAX_ASPECT}:1 between them"
        )
    return image
