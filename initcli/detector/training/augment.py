"""Training-time image handling: reading, HSV jitter, random letterbox placement, camera degradation."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from initcli.detector.preprocess import PAD_VALUE
from initcli.io.images import read_image

__all__ = ["augment_hsv", "camera_degrade", "random_letterbox", "read_image_rgb"]


def read_image_rgb(path: Path) -> np.ndarray:
    return cv2.cvtColor(read_image(path), cv2.COLOR_BGR2RGB)


def augment_hsv(img: np.ndarray, gains: tuple[float, float, float], rng: np.random.Generator) -> np.ndarray:
    r = rng.uniform(-1, 1, 3) * np.array(gains) + 1
    hue, sat, val = cv2.split(cv2.cvtColor(img, cv2.COLOR_RGB2HSV))
    x = np.arange(0, 256, dtype=r.dtype)
    lut_hue = ((x * r[0]) % 180).astype(np.uint8)
    lut_sat = np.clip(x * r[1], 0, 255).astype(np.uint8)
    lut_val = np.clip(x * r[2], 0, 255).astype(np.uint8)
    hsv = cv2.merge((cv2.LUT(hue, lut_hue), cv2.LUT(sat, lut_sat), cv2.LUT(val, lut_val)))
    return cv2.cvtColor(hsv, cv2.COLOR_HSV2RGB)


def random_letterbox(
    img: np.ndarray,
    boxes: np.ndarray,
    size: int,
    scale: tuple[float, float],
    rng: np.random.Generator,
    perspective: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scale by a random factor around the letterbox fit and place at random; boxes in pixels.

    With ``perspective`` > 0, also a random homography: corners moved by up to that fraction of the
    image, a small rotation (a tilted, rolled camera); boxes become the bounds of their warped corners.
    Scales above 1 crop. Returns the image, the boxes (x1 y1 x2 y2 pixels, clipped) and a mask of
    the boxes kept (at least 35 % of their area and 2 px on each side inside the image).
    """
    h, w = img.shape[:2]
    r = size / max(h, w) * rng.uniform(*scale)
    nw, nh = w * r, h * r
    ox = rng.uniform(min(0.0, size - nw), max(0.0, size - nw))
    oy = rng.uniform(min(0.0, size - nh), max(0.0, size - nh))
    m = np.array([[r, 0, ox], [0, r, oy], [0, 0, 1]], dtype=np.float64)
    if perspective > 0:
        src = np.array([[0, 0], [size, 0], [size, size], [0, size]], dtype=np.float32)
        dst = src + rng.uniform(-perspective, perspective, (4, 2)).astype(np.float32) * size
        a = np.deg2rad(rng.uniform(-5, 5))
        c, s_ = np.cos(a), np.sin(a)
        rot = np.array(
            [
                [c, -s_, (1 - c) * size / 2 + s_ * size / 2],
                [s_, c, (1 - c) * size / 2 - s_ * size / 2],
                [0, 0, 1],
            ]
        )
        m = rot @ cv2.getPerspectiveTransform(src, dst).astype(np.float64) @ m
    out = cv2.warpPerspective(
        img,
        m,
        (size, size),
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=(PAD_VALUE, PAD_VALUE, PAD_VALUE),
    )
    px = boxes.reshape(-1, 4) * np.array([w, h, w, h])
    corners = np.stack([px[:, [0, 1]], px[:, [2, 1]], px[:, [2, 3]], px[:, [0, 3]]], axis=1)  # (n, 4, 2)
    hom = np.concatenate([corners, np.ones(corners.shape[:2] + (1,))], axis=2) @ m.T
    xy = hom[..., :2] / hom[..., 2:3]
    b = np.column_stack([xy[..., 0].min(1), xy[..., 1].min(1), xy[..., 0].max(1), xy[..., 1].max(1)])
    area0 = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    c = np.clip(b, 0, size)
    area1 = (c[:, 2] - c[:, 0]) * (c[:, 3] - c[:, 1])
    keep = (area1 >= 0.35 * np.maximum(area0, 1e-9)) & (c[:, 2] - c[:, 0] >= 2) & (c[:, 3] - c[:, 1] >= 2)
    return out, c, keep


def camera_degrade(img: np.ndarray, p: float, rng: np.random.Generator) -> np.ndarray:
    """What real cameras do to an image, each with chance ``p``: gamma / contrast, colour cast,
    Gaussian or motion blur, sensor noise, JPEG compression."""
    out: np.ndarray = img.astype(np.float32)
    if rng.random() < p:  # exposure curve and contrast
        out = 255.0 * (out / 255.0) ** rng.uniform(0.6, 1.6)
        out = (out - 128.0) * rng.uniform(0.7, 1.3) + 128.0
    if rng.random() < p * 0.6:  # white balance
        out = out * rng.uniform(0.85, 1.15, 3)[None, None, :]
    out = np.clip(out, 0, 255).astype(np.uint8)
    if rng.random() < p * 0.6:
        if rng.random() < 0.5:
            out = cv2.GaussianBlur(out, (0, 0), rng.uniform(0.5, 1.8))
        else:  # motion blur of a moving robot
            k = int(rng.integers(3, 9))
            kernel: np.ndarray = np.zeros((k, k), np.float32)
            kernel[k // 2, :] = 1.0 / k
            rot = cv2.getRotationMatrix2D((k / 2 - 0.5, k / 2 - 0.5), rng.uniform(0, 180), 1.0)
            kernel = cv2.warpAffine(kernel, rot, (k, k))
            out = cv2.filter2D(out, -1, (kernel / max(float(kernel.sum()), 1e-6)).astype(np.float32))
    if rng.random() < p * 0.6:
        noise = rng.normal(0.0, rng.uniform(2.0, 12.0), out.shape)
        out = np.clip(out.astype(np.float32) + noise, 0, 255).astype(np.uint8)
    if rng.random() < p * 0.5:
        ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(35, 90))])
        decoded = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED) if ok else None
        if decoded is not None:
            out = decoded
    return out
