"""Letterbox preprocessing shared by training, validation and the onnxruntime detector (no torch).

Ultralytics' convention: scale the image to fit ``(height, width)`` keeping its aspect ratio,
centre it, pad with grey 114, RGB, values / 255, NCHW float32.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["Letterbox", "PAD_VALUE", "letterbox", "to_tensor_layout"]

PAD_VALUE = 114


@dataclass(frozen=True)
class Letterbox:
    """How an image was fitted into the network input: ``input = image * scale + (pad_x, pad_y)``."""

    scale: float
    pad_x: float
    pad_y: float
    scale_y: float | None = None  # a plain resize (no letterbox) scales x and y differently

    def to_image(self, boxes: np.ndarray) -> np.ndarray:
        """Boxes ``x1 y1 x2 y2`` in network-input pixels -> original image pixels."""
        b = np.asarray(boxes, dtype=np.float32).reshape(-1, 4).copy()
        b[:, [0, 2]] = (b[:, [0, 2]] - self.pad_x) / self.scale
        b[:, [1, 3]] = (b[:, [1, 3]] - self.pad_y) / (self.scale if self.scale_y is None else self.scale_y)
        return b


def letterbox(
    image: np.ndarray, size: tuple[int, int], pad_value: int = PAD_VALUE
) -> tuple[np.ndarray, Letterbox]:
    """Fit ``image`` (H, W, 3) into ``size`` = (height, width), centred, padded with ``pad_value``."""
    h, w = image.shape[:2]
    th, tw = size
    r = min(th / h, tw / w)
    nw, nh = max(1, int(round(w * r))), max(1, int(round(h * r)))  # a sliver stays one pixel wide
    if (nw, nh) != (w, h):
        image = cv2.resize(image, (nw, nh), interpolation=cv2.INTER_LINEAR)
    dw, dh = (tw - nw) / 2.0, (th - nh) / 2.0
    top, bottom = int(round(dh - 0.1)), int(round(dh + 0.1))
    left, right = int(round(dw - 0.1)), int(round(dw + 0.1))
    out = cv2.copyMakeBorder(
        image, top, bottom, left, right, cv2.BORDER_CONSTANT, value=(pad_value, pad_value, pad_value)
    )
    return out, Letterbox(r, float(left), float(top))


def to_tensor_layout(
    image_rgb: np.ndarray, scale: float = 1.0 / 255.0, dtype: type = np.float32
) -> np.ndarray:
    """(H, W, 3) uint8 -> (1, 3, H, W) float, multiplied by ``scale``."""
    x: np.ndarray = np.ascontiguousarray(image_rgb.transpose(2, 0, 1)[None], dtype=dtype)
    x *= scale
    return x
