"""Detection metrics per class: precision and recall at a score threshold, AP at IoU 0.5.

Predictions are matched to ground truth greedily by descending score, each ground-truth box at
most once, same class, IoU >= 0.5 (PASCAL VOC / COCO ``AP50``). AP is the area under the
precision envelope sampled at 101 recall points (COCO). mAP@0.5 is the mean over the classes
that have ground-truth boxes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from initcli.detector import DETECTOR_CONFIDENCE
from initcli.detector.layouts import iou_matrix

__all__ = ["ClassMetrics", "MetricAccumulator", "Metrics", "average_precision"]


@dataclass
class ClassMetrics:
    name: str
    instances: int
    precision: float | None
    recall: float | None
    ap50: float | None
    detections: int = 0


@dataclass
class Metrics:
    classes: list[ClassMetrics]
    images: int
    conf: float
    map50: float | None = None
    extra: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            "map50": _round(self.map50),
            "images": self.images,
            "conf": self.conf,
            "classes": {
                c.name: {
                    "precision": _round(c.precision),
                    "recall": _round(c.recall),
                    "ap50": _round(c.ap50),
                    "instances": c.instances,
                }
                for c in self.classes
            },
        }


def _round(v: float | None) -> float | None:
    return None if v is None else round(float(v), 4)


def average_precision(tp: np.ndarray, scores: np.ndarray, n_gt: int) -> float:
    """101-point interpolated AP from per-detection true-positive flags and scores."""
    if n_gt == 0:
        return float("nan")
    if len(tp) == 0:
        return 0.0
    order = np.argsort(-scores, kind="stable")
    tp = tp[order].astype(np.float64)
    ctp = np.cumsum(tp)
    recall = ctp / n_gt
    precision = ctp / np.arange(1, len(tp) + 1)
    envelope = np.flip(np.maximum.accumulate(np.flip(precision)))
    x = np.linspace(0, 1, 101)
    idx = np.searchsorted(recall, x, side="left")
    valid = idx < len(recall)
    return float(np.where(valid, envelope[np.clip(idx, 0, len(recall) - 1)], 0.0).mean())


class MetricAccumulator:
    """Collects per-image predictions and ground truth; :meth:`compute` gives :class:`Metrics`."""

    def __init__(self, nc: int, iou: float = 0.5) -> None:
        self.nc, self.iou = nc, iou
        self.scores: list[list[float]] = [[] for _ in range(nc)]
        self.tp: list[list[bool]] = [[] for _ in range(nc)]
        self.n_gt = np.zeros(nc, dtype=np.int64)
        self.images = 0

    def add(
        self,
        boxes: np.ndarray,
        scores: np.ndarray,
        classes: np.ndarray,
        gt_boxes: np.ndarray,
        gt_classes: np.ndarray,
    ) -> None:
        """One image: predicted boxes (x1 y1 x2 y2), scores, classes and its ground truth (same units)."""
        self.images += 1
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        scores = np.asarray(scores, dtype=np.float64).reshape(-1)
        classes = np.asarray(classes, dtype=np.int64).reshape(-1)
        gt_boxes = np.asarray(gt_boxes, dtype=np.float64).reshape(-1, 4)
        gt_classes = np.asarray(gt_classes, dtype=np.int64).reshape(-1)
        for c in range(self.nc):
            gmask = gt_classes == c
            self.n_gt[c] += int(gmask.sum())
            pmask = classes == c
            if not pmask.any():
                continue
            pb, ps = boxes[pmask], scores[pmask]
            order = np.argsort(-ps, kind="stable")
            pb, ps = pb[order], ps[order]
            gb = gt_boxes[gmask]
            used = np.zeros(len(gb), dtype=bool)
            ious = iou_matrix(pb, gb) if len(gb) else np.zeros((len(pb), 0))
            for k in range(len(pb)):
                hit = False
                if len(gb):
                    cand = np.where(used, -1.0, ious[k])
                    j = int(np.argmax(cand))
                    if cand[j] >= self.iou:
                        used[j] = True
                        hit = True
                self.tp[c].append(hit)
                self.scores[c].append(float(ps[k]))

    def compute(self, names: list[str], conf: float = DETECTOR_CONFIDENCE) -> Metrics:
        out = []
        aps = []
        for c in range(self.nc):
            tp = np.array(self.tp[c], dtype=bool)
            sc = np.array(self.scores[c], dtype=np.float64)
            n_gt = int(self.n_gt[c])
            above = sc >= conf
            n_det = int(above.sum())
            tp_at = int(tp[above].sum())
            precision = tp_at / n_det if n_det else (None if n_gt == 0 else 0.0)
            recall = tp_at / n_gt if n_gt else None
            ap = average_precision(tp, sc, n_gt) if n_gt else None
            if ap is not None:
                aps.append(ap)
            name = names[c] if c < len(names) else f"class{c}"
            out.append(ClassMetrics(name, n_gt, precision, recall, ap, n_det))
        return Metrics(out, self.images, conf, float(np.mean(aps)) if aps else None)
