"""``bim-init detector calibrate``: measure a model's errors on labelled images as a
:class:`~initcli.detector.profile.DetectorProfile` (recall by box height, false boxes per image,
class confusion, scores), the profile the simulated detector draws from (``sim.detector.profile``).

A detection finds a labelled box when it scores at least ``conf`` and overlaps it by IoU ``iou`` or
more, whatever its class (greedily, best score first, each labelled box at most once): recall is
whether a thing is seen, the confusion matrix what it is called. Every other detection at or above
``conf`` is a false box (on DoorDetect, detections of its handles, cabinet and refrigerator doors,
whose boxes the dataset's mapping drops, are false boxes). Box heights are measured in pixels of
the model's input (the letterboxed image); each class's bins are the fine ones of :data:`FINE_EDGES`
merged until every bin holds :data:`MIN_BOXES` boxes, so that no bin's recall rests on a handful.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from bimkit.documents import file_sha256
from bimkit.errors import InputError
from initcli.core.features.classes import ClassMap
from initcli.detector import DETECTOR_CONFIDENCE
from initcli.detector.layouts import iou_matrix
from initcli.detector.profile import ALL, DetectorProfile, RecallTable

__all__ = ["FINE_EDGES", "MIN_BOXES", "ProfileAccumulator", "calibrate_model", "merged_edges"]

# px of the model's input: the finest bins of box height (cut at the input's height)
FINE_EDGES = (0.0, 8.0, 16.0, 24.0, 32.0, 48.0, 64.0, 96.0, 128.0, 160.0, 192.0, 256.0, 320.0, 480.0, 640.0)
MIN_BOXES = 8  # labelled boxes a bin must hold (fine bins are merged up to this)
QUANTILES = 21  # score quantiles kept (0, 5 %, ..., 100 %)


class _Model(Protocol):
    """What calibration needs of a detector (:class:`initcli.detector.runtime.Detector` has it)."""

    names: list[str]
    input_size: tuple[int, int]  # (height, width)
    path: Path

    def detect(self, image_bgr: np.ndarray, conf: float | None = None) -> Sequence: ...


def merged_edges(heights: Sequence[float], top: float, min_boxes: int = MIN_BOXES) -> tuple[float, ...]:
    """Bin edges over [0, ``top``]: the fine edges below ``top``, neighbours merged (from the
    shortest boxes up) until each bin holds ``min_boxes`` of ``heights``; a short remainder joins
    the last bin."""
    fine = [e for e in FINE_EDGES if e < top] + [float(top)]
    table = RecallTable(tuple(fine), (0,) * (len(fine) - 1), (0,) * (len(fine) - 1))
    counts = Counter(table.bin_of(h) for h in heights)
    edges, held = [fine[0]], 0
    for k in range(len(fine) - 1):
        held += counts.get(k, 0)
        if held >= min_boxes:
            edges.append(fine[k + 1])
            held = 0
    if len(edges) == 1:
        edges.append(fine[-1])
    else:
        edges[-1] = fine[-1]
    return tuple(edges)


@dataclass
class ProfileAccumulator:
    """Collects images' labelled boxes and detections; :meth:`profile` gives the profile."""

    input_width: int
    input_height: int
    conf: float = DETECTOR_CONFIDENCE
    iou: float = 0.5
    images: int = 0
    heights: dict[str, list[float]] = field(default_factory=dict)  # px of the model's input
    found: dict[str, list[bool]] = field(default_factory=dict)
    confusion: dict[str, Counter] = field(default_factory=dict)
    false: Counter = field(default_factory=Counter)
    true_scores: list[float] = field(default_factory=list)
    false_scores: list[float] = field(default_factory=list)

    def add(
        self,
        size: tuple[int, int],
        gt_boxes: np.ndarray,
        gt_classes: Sequence[str],
        boxes: np.ndarray,
        scores: np.ndarray,
        classes: Sequence[str],
    ) -> None:
        """One image of ``size`` (width, height): labelled boxes (x1 y1 x2 y2 px) and their classes,
        the detections' boxes, scores and classes (canonical names)."""
        self.images += 1
        scale = min(self.input_width / size[0], self.input_height / size[1])
        gt_boxes = np.asarray(gt_boxes, dtype=np.float64).reshape(-1, 4)
        boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
        scores = np.asarray(scores, dtype=np.float64).reshape(-1)
        keep = np.flatnonzero(scores >= self.conf)
        order = keep[np.argsort(-scores[keep], kind="stable")]
        ious = iou_matrix(boxes[order], gt_boxes) if len(gt_boxes) and len(order) else None
        hit = np.zeros(len(gt_boxes), dtype=bool)
        given: dict[int, str] = {}
        for row, k in enumerate(order):
            if ious is not None:
                cand = np.where(hit, -1.0, ious[row])
                j = int(np.argmax(cand))
                if cand[j] >= self.iou:
                    hit[j] = True
                    given[j] = classes[k]
                    self.true_scores.append(float(scores[k]))
                    continue
            self.false[classes[k]] += 1
            self.false_scores.append(float(scores[k]))
        for j, cls in enumerate(gt_classes):
            self.heights.setdefault(cls, []).append(float(gt_boxes[j, 3] - gt_boxes[j, 1]) * scale)
            self.found.setdefault(cls, []).append(bool(hit[j]))
            if hit[j]:
                self.confusion.setdefault(cls, Counter())[given[j]] += 1

    def _table(self, heights: list[float], found: list[bool]) -> RecallTable:
        edges = merged_edges(heights, self.input_height)
        empty = RecallTable(edges, (0,) * (len(edges) - 1), (0,) * (len(edges) - 1))
        boxes, hits = [0] * (len(edges) - 1), [0] * (len(edges) - 1)
        for h, f in zip(heights, found, strict=True):
            k = empty.bin_of(h)
            boxes[k] += 1
            hits[k] += int(f)
        return RecallTable(edges, tuple(boxes), tuple(hits))

    def profile(
        self, model: str, sha256: str, classes: Sequence[str], data: str, split: str
    ) -> DetectorProfile:
        if self.images == 0:
            raise InputError(f"{data}: no images to calibrate on")
        recall = {cls: self._table(self.heights[cls], self.found[cls]) for cls in sorted(self.heights)}
        pooled_h = [h for cls in sorted(self.heights) for h in self.heights[cls]]
        pooled_f = [f for cls in sorted(self.found) for f in self.found[cls]]
        recall[ALL] = self._table(pooled_h, pooled_f)
        q = np.linspace(0.0, 1.0, QUANTILES)
        return DetectorProfile(
            model=model,
            sha256=sha256,
            classes=tuple(classes),
            input_width=self.input_width,
            input_height=self.input_height,
            data=data,
            split=split,
            images=self.images,
            conf=self.conf,
            iou=self.iou,
            recall=recall,
            false_boxes={c: self.false[c] / self.images for c in sorted(set(classes) | set(self.false))},
            confusion={c: dict(sorted(n.items())) for c, n in sorted(self.confusion.items())},
            true_scores=tuple(np.quantile(self.true_scores, q).tolist()) if self.true_scores else (),
            false_scores=tuple(np.quantile(self.false_scores, q).tolist()) if self.false_scores else (),
            boxes={c: len(h) for c, h in sorted(self.heights.items())},
        )


def calibrate_model(
    model: str | Path,
    data: Path,
    split: str = "val",
    conf: float = DETECTOR_CONFIDENCE,
    iou: float = 0.5,
    max_images: int = 0,
    threads: int = 2,
    detector: _Model | None = None,
) -> tuple[DetectorProfile, list[str]]:
    """The profile of ``model`` (or of ``detector``, a stand-in for tests) on a dataset split, and
    warnings (dataset classes the model has no class for)."""
    from initcli.detector.datasets import load_dataset
    from initcli.io.images import read_image

    ds = load_dataset(data)
    items = ds.split(split)[: max_images or None]
    if not items:
        raise InputError(f"{data}: the {split} split has no images")
    if detector is None:
        from initcli.detector.runtime import Detector

        detector = Detector(model, conf=conf, iou=0.5, max_det=100, threads=threads)
    cmap = ClassMap()
    names = [cmap.canonical(n) for n in detector.names]
    ds_names = [cmap.canonical(n) for n in ds.names]
    counts = ds.instance_counts(split)
    lacking = [n for n, k in zip(ds_names, counts, strict=True) if k and n not in names]
    warnings = [f"the model has no class for {lacking}: their boxes can only be found as another class"]
    acc = ProfileAccumulator(detector.input_size[1], detector.input_size[0], conf, iou)
    for item in items:
        img = read_image(item.image)
        h, w = img.shape[:2]
        found = detector.detect(img, conf)
        acc.add(
            (w, h),
            item.boxes.astype(np.float64) * np.array([w, h, w, h]),
            [ds_names[int(c)] for c in item.classes],
            np.array([d.box for d in found], dtype=np.float64).reshape(-1, 4),
            np.array([d.score for d in found], dtype=np.float64),
            [
                names[d.class_id] if 0 <= d.class_id < len(names) else cmap.canonical(d.class_name)
                for d in found
            ],
        )
    path = Path(detector.path)
    profile = acc.profile(path.name, file_sha256(path), names, str(data), split)
    return profile, warnings if lacking else []
