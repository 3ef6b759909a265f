"""Output layouts of detection ONNX models, their decoding and class-aware NMS (numpy, no torch).

Supported, recognised from the output's shape and the model metadata:

- ``yolov8``: ``[1, 4 + nc, N]`` -- ``cx, cy, w, h`` in input pixels then one score per class, no
  objectness (Ultralytics YOLOv8 / YOLO11 and our own exports).
- ``yolov8t``: the same transposed, ``[1, N, 4 + nc]``.
- ``yolov5``: ``[1, N, 5 + nc]`` -- ``cx, cy, w, h, objectness`` then class scores.
- ``nms``: ``[1, N, 6]`` -- ``x1, y1, x2, y2, score, class`` after NMS in the graph (Ultralytics
  ``nms=True``, many end-to-end exports); rows with score 0 are padding.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LAYOUTS", "LayoutError", "MAX_WH", "box_iou", "decode", "infer_layout", "iou_matrix", "nms"]

LAYOUTS = ("yolov8", "yolov8t", "yolov5", "nms")
MAX_WH = 7680.0  # class offset for class-aware NMS in one pass


class LayoutError(ValueError):
    """The output shape fits no supported layout."""


def infer_layout(shape: tuple[int, ...], nc: int | None, hint: str | None = None) -> tuple[str, int]:
    """The layout and number of classes of an output of concrete ``shape`` (batch first)."""
    if hint in LAYOUTS:
        layout = hint
    elif len(shape) != 3:
        raise LayoutError(f"output of shape {list(shape)}: expected 3 dimensions [1, ..., ...]")
    else:
        a, b = int(shape[1]), int(shape[2])
        if a < b and a > 4 and (nc is None or a == 4 + nc):
            layout = "yolov8"
        elif a > b and b == 6:  # also with 2 classes: a transposed YOLOv8 output is rare, NMS exports common
            layout = "nms"
        elif a > b and nc is not None and b == 4 + nc:
            layout = "yolov8t"
        elif a > b and b > 5 and (nc is None or b == 5 + nc):
            layout = "yolov5"
        else:
            want = f"nc={nc}" if nc is not None else "names unknown"
            raise LayoutError(
                f"output of shape {list(shape)} ({want}) fits no supported layout: [1, 4+nc, N] (YOLOv8/11), "
                "[1, N, 5+nc] (YOLOv5) or [1, N, 6] (NMS in the graph)"
            )
    if len(shape) != 3:
        raise LayoutError(f"output of shape {list(shape)}: expected 3 dimensions")
    a, b = int(shape[1]), int(shape[2])
    classes = {"yolov8": a - 4, "yolov8t": b - 4, "yolov5": b - 5, "nms": nc or 0}[layout]
    if layout != "nms" and classes < 1:
        raise LayoutError(f"output of shape {list(shape)} has no class scores for layout {layout}")
    return layout, classes


def _xywh_to_xyxy(b: np.ndarray) -> np.ndarray:
    out = np.empty_like(b)
    out[:, 0] = b[:, 0] - b[:, 2] / 2
    out[:, 1] = b[:, 1] - b[:, 3] / 2
    out[:, 2] = b[:, 0] + b[:, 2] / 2
    out[:, 3] = b[:, 1] + b[:, 3] / 2
    return out


def decode(output: np.ndarray, layout: str, conf: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One image's raw output (batch dim included or not) -> boxes x1y1x2y2 (input px), scores, classes.

    Candidates scoring below ``conf`` are dropped; no NMS here (see :func:`nms`).
    """
    out = np.asarray(output, dtype=np.float32)
    if out.ndim == 3:
        out = out[0]
    if layout == "yolov8":
        out = out.T
        layout = "yolov8t"
    if layout == "yolov8t":
        cls = out[:, 4:]
        classes = cls.argmax(axis=1)
        scores = cls[np.arange(len(cls)), classes]
        keep = scores >= conf
        return _xywh_to_xyxy(out[keep, :4]), scores[keep], classes[keep]
    if layout == "yolov5":
        obj = out[:, 4]
        cand = obj >= conf
        out = out[cand]
        cls = out[:, 5:] * out[:, 4:5]
        classes = cls.argmax(axis=1)
        scores = cls[np.arange(len(cls)), classes]
        keep = scores >= conf
        return _xywh_to_xyxy(out[keep, :4]), scores[keep], classes[keep]
    if layout == "nms":
        keep = out[:, 4] >= max(conf, 1e-9)
        return out[keep, :4].copy(), out[keep, 4], out[keep, 5].astype(np.int64)
    raise LayoutError(f"unknown layout {layout!r}")


def box_iou(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """IoU of one box (4,) with many (M, 4), all x1 y1 x2 y2."""
    ix1 = np.maximum(box[0], boxes[:, 0])
    iy1 = np.maximum(box[1], boxes[:, 1])
    ix2 = np.minimum(box[2], boxes[:, 2])
    iy2 = np.minimum(box[3], boxes[:, 3])
    inter = np.clip(ix2 - ix1, 0, None) * np.clip(iy2 - iy1, 0, None)
    area = (box[2] - box[0]) * (box[3] - box[1])
    areas = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    return inter / np.maximum(area + areas - inter, 1e-9)


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pairwise IoU (len(a), len(b)) of x1 y1 x2 y2 boxes."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    ix1 = np.maximum(a[:, None, 0], b[None, :, 0])
    iy1 = np.maximum(a[:, None, 1], b[None, :, 1])
    ix2 = np.minimum(a[:, None, 2], b[None, :, 2])
    iy2 = np.minimum(a[:, None, 3], b[None, :, 3])
    inter = np.clip(ix2 - ix1, 0, None) * np.clip(iy2 - iy1, 0, None)
    area_a = (a[:, 2] - a[:, 0]) * (a[:, 3] - a[:, 1])
    area_b = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    return inter / np.maximum(area_a[:, None] + area_b[None, :] - inter, 1e-9)


def nms(
    boxes: np.ndarray,
    scores: np.ndarray,
    classes: np.ndarray,
    iou: float = 0.5,
    max_det: int = 100,
    max_candidates: int = 3000,
) -> np.ndarray:
    """Class-aware greedy NMS; indices of the kept boxes, best first."""
    if len(scores) == 0:
        return np.zeros(0, dtype=np.int64)
    order = np.argsort(-scores, kind="stable")[:max_candidates]
    shifted = boxes + (classes.astype(np.float32) * MAX_WH)[:, None]
    keep: list[int] = []
    while len(order):
        i = int(order[0])
        keep.append(i)
        if len(keep) >= max_det or len(order) == 1:
            break
        rest = order[1:]
        order = rest[box_iou(shifted[i], shifted[rest]) <= iou]
    return np.array(keep, dtype=np.int64)
