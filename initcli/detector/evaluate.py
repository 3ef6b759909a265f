"""``bim-init detector eval``: an ONNX model on a labelled dataset, through the runtime (no torch).

Model classes are matched to dataset classes by name (case and the built-in synonyms ignored:
``Door``/``doors``, ``elevator``/``lift``, ``staircase``/``stairs``); detections of classes the
dataset does not have are ignored, dataset classes the model does not know score 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bimkit.errors import InputError
from initcli.core.features.classes import ClassMap
from initcli.detector import DETECTOR_CONFIDENCE
from initcli.detector.datasets import load_dataset
from initcli.detector.metrics import MetricAccumulator, Metrics
from initcli.detector.runtime import Detector
from initcli.io.images import read_image

__all__ = ["EvalResult", "evaluate_model"]


@dataclass
class EvalResult:
    metrics: Metrics
    model: str
    data: str
    split: str
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        doc = self.metrics.to_dict()
        doc.update({"model": self.model, "data": self.data, "split": self.split})
        return doc


def evaluate_model(
    model: str | Path,
    data: Path,
    split: str = "val",
    conf: float = DETECTOR_CONFIDENCE,
    iou: float = 0.5,
    max_images: int = 0,
    threads: int = 2,
) -> EvalResult:
    ds = load_dataset(data)
    items = ds.split(split)
    if max_images > 0:
        items = items[:max_images]
    if not items:
        raise InputError(f"{data}: the {split} split has no images")
    det = Detector(model, conf=0.001, iou=iou, max_det=100, threads=threads)
    cmap = ClassMap()
    ds_index = {cmap.canonical(n): i for i, n in enumerate(ds.names)}
    model_to_ds = {k: ds_index.get(cmap.canonical(n), -1) for k, n in enumerate(det.names)}
    warnings = []
    unknown = [n for n in ds.names if cmap.canonical(n) not in {cmap.canonical(m) for m in det.names}]
    if unknown:
        warnings.append(f"the model has no class for {unknown}: they score 0")
    acc = MetricAccumulator(len(ds.names))
    for item in items:
        img = read_image(item.image)
        h, w = img.shape[:2]
        found = det.detect(img)
        cls = np.array([model_to_ds.get(d.class_id, -1) for d in found], dtype=np.int64)
        keep = cls >= 0
        boxes = np.array([d.box for d in found], dtype=np.float64).reshape(-1, 4)[keep]
        scores = np.array([d.score for d in found], dtype=np.float64)[keep]
        gt = item.boxes.astype(np.float64) * np.array([w, h, w, h])
        acc.add(boxes, scores, cls[keep], gt, item.classes)
    return EvalResult(acc.compute(ds.names, conf), str(model), str(data), split, warnings)
