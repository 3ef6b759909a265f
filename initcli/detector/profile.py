"""A detector profile: what a model gets right and wrong, measured on labelled images
(``bim-init detector calibrate``, :mod:`initcli.detector.calibrate`) and drawn from by the simulated
detector (``sim.detector.profile``, :class:`initcli.sim.camera.SimulatedDetector`).

Recall is binned by the box height in pixels of the model's input (the letterboxed image): the
simulator turns a feature's distance and height into its box height through the camera's
intrinsics and scales it to the model's input, so a profile measured on photos of any size
transfers to a camera of another resolution or field of view. False boxes are counted per image
and per class the model gave them; the confusion matrix counts the classes given to the boxes it
found; scores are kept as quantiles. The file format: ``bimkit/schemas/detector_profile.schema.json``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bimkit.atomic import write_text_atomic
from bimkit.documents import read_json
from bimkit.errors import InputError
from bimkit.schemas import schema_path, validate_document
from initcli.detector import MODELS_DIR

__all__ = [
    "PROFILE_FORMAT",
    "PROFILE_NAMES",
    "PROFILE_SCHEMA",
    "DetectorProfile",
    "RecallTable",
    "read_profile",
    "resolve_profile",
    "write_profile",
]

PROFILE_FORMAT = "bim-init.detector-profile/1"
PROFILE_SCHEMA = schema_path("detector_profile.schema.json")
# The profiles shipped beside the default model (``make profiles`` measures them again).
PROFILE_NAMES: dict[str, Path] = {
    "default-real": MODELS_DIR / "default.real.profile.json",
    "default-renders": MODELS_DIR / "default.renders.profile.json",
}
ALL = "all"  # the recall table of every class pooled


@dataclass(frozen=True)
class RecallTable:
    """Labelled boxes and those found, binned by box height (px of the model's input): bin k holds
    heights from ``edges[k]`` up to ``edges[k + 1]``; shorter boxes count in the first bin, taller
    ones in the last."""

    edges: tuple[float, ...]
    boxes: tuple[int, ...]
    found: tuple[int, ...]

    def bin_of(self, height: float) -> int:
        k = int(np.searchsorted(self.edges, height, side="right")) - 1
        return min(max(k, 0), len(self.boxes) - 1)

    def recall(self, height: float) -> float:
        """The share of boxes this tall that the model found (0 in a bin without boxes)."""
        k = self.bin_of(height)
        return self.found[k] / self.boxes[k] if self.boxes[k] else 0.0

    def to_dict(self) -> dict[str, Any]:
        return {
            "edges": [round(e, 3) for e in self.edges],
            "boxes": list(self.boxes),
            "found": list(self.found),
        }


@dataclass(frozen=True)
class DetectorProfile:
    """A model's errors on a dataset (see the module's docstring); class names canonical."""

    model: str
    sha256: str
    classes: tuple[str, ...]  # the model's classes
    input_width: int
    input_height: int
    data: str
    split: str
    images: int
    conf: float
    iou: float
    recall: dict[str, RecallTable]  # per labelled class, and ALL
    false_boxes: dict[str, float]  # per image, by the class the model gave them
    confusion: dict[str, dict[str, int]]  # labelled class -> {given class: found boxes}
    true_scores: tuple[float, ...] = ()  # quantiles
    false_scores: tuple[float, ...] = ()
    boxes: dict[str, int] = field(default_factory=dict)  # labelled boxes per class
    note: str = ""

    # --- what the simulated detector draws ---------------------------------------------------------

    def input_scale(self, width: int, height: int) -> float:
        """Pixels of the model's input per pixel of a ``width`` x ``height`` image (the letterbox)."""
        return min(self.input_width / width, self.input_height / height)

    def recall_of(self, cls: str, height: float) -> float:
        """Chance that a box of class ``cls``, ``height`` px of the model's input tall, is found."""
        return (self.recall.get(cls) or self.recall[ALL]).recall(height)

    def given_class(self, cls: str, rng: np.random.Generator) -> str:
        """The class the model gives a found box of class ``cls`` (drawn from the confusion matrix;
        ``cls`` itself where the profile has no row for it)."""
        row = self.confusion.get(cls) or {}
        total = sum(row.values())
        if total <= 0:
            return cls
        names = sorted(row)
        p = np.array([row[n] for n in names], dtype=float) / total
        return names[int(rng.choice(len(names), p=p))]

    def false_boxes_per_image(self) -> float:
        return float(sum(self.false_boxes.values()))

    def score(self, rng: np.random.Generator, true: bool) -> float:
        """A score drawn from the quantiles of true (found) or false boxes' scores."""
        q = self.true_scores if true else self.false_scores
        if not q:
            return 0.5 * (self.conf + 1.0)
        value = float(np.interp(rng.random(), np.linspace(0.0, 1.0, len(q)), q))
        return min(max(value, self.conf), 1.0)

    # --- the file ----------------------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        dataset: dict[str, Any] = {
            "data": self.data,
            "split": self.split,
            "images": self.images,
            "boxes": dict(self.boxes),
        }
        if self.note:
            dataset["note"] = self.note
        return {
            "format": PROFILE_FORMAT,
            "model": {
                "name": self.model,
                "sha256": self.sha256,
                "classes": list(self.classes),
                "input": {"width": self.input_width, "height": self.input_height},
            },
            "dataset": dataset,
            "conf": self.conf,
            "iou": self.iou,
            "recall": {k: t.to_dict() for k, t in self.recall.items()},
            "false_boxes": {
                "per_image": round(self.false_boxes_per_image(), 5),
                "classes": {k: round(v, 5) for k, v in self.false_boxes.items()},
            },
            "confusion": {k: dict(v) for k, v in self.confusion.items()},
            "scores": {
                "true": [round(s, 4) for s in self.true_scores],
                "false": [round(s, 4) for s in self.false_scores],
            },
        }

    @staticmethod
    def from_dict(doc: dict[str, Any], where: str) -> DetectorProfile:
        """A profile from its (schema-valid) document; tables whose lengths disagree are refused."""
        recall = {}
        for name, t in doc["recall"].items():
            edges, boxes, found = t["edges"], t["boxes"], t["found"]
            if len(edges) != len(boxes) + 1 or len(found) != len(boxes):
                raise InputError(
                    f"{where}: recall.{name}: expected one more edge than bins and as many found as boxes"
                    f" (edges {len(edges)}, boxes {len(boxes)}, found {len(found)})"
                )
            if any(b > a for a, b in zip(edges[1:], edges, strict=False)):
                raise InputError(f"{where}: recall.{name}.edges: must not decrease")
            if any(f > b for f, b in zip(found, boxes, strict=True)):
                raise InputError(f"{where}: recall.{name}: more boxes found than there are in a bin")
            recall[name] = RecallTable(tuple(map(float, edges)), tuple(boxes), tuple(found))
        model, dataset = doc["model"], doc["dataset"]
        return DetectorProfile(
            model=model["name"],
            sha256=model["sha256"],
            classes=tuple(model["classes"]),
            input_width=int(model["input"]["width"]),
            input_height=int(model["input"]["height"]),
            data=dataset["data"],
            split=dataset["split"],
            images=int(dataset["images"]),
            conf=float(doc["conf"]),
            iou=float(doc["iou"]),
            recall=recall,
            false_boxes={k: float(v) for k, v in doc["false_boxes"]["classes"].items()},
            confusion={k: {c: int(n) for c, n in row.items()} for k, row in doc["confusion"].items()},
            true_scores=tuple(float(s) for s in doc["scores"]["true"]),
            false_scores=tuple(float(s) for s in doc["scores"]["false"]),
            boxes={k: int(v) for k, v in dataset["boxes"].items()},
            note=str(dataset.get("note", "")),
        )


def resolve_profile(name: str, base: Path | None = None) -> Path:
    """``default-real`` / ``default-renders`` -> the shipped profile; anything else a path (relative
    to ``base``, the folder of the config that names it)."""
    key = name.strip().lower()
    if key in PROFILE_NAMES:
        return PROFILE_NAMES[key]
    path = Path(name).expanduser()
    return path if path.is_absolute() or base is None else base / path


def read_profile(path: Path) -> DetectorProfile:
    """The profile at ``path``; a missing, unreadable or malformed file is one :class:`InputError`."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such detector profile (bim-init detector calibrate writes one)")
    doc = read_json(path, "a detector profile (JSON)")
    validate_document(doc, PROFILE_SCHEMA, str(path))
    return DetectorProfile.from_dict(doc, str(path))


def write_profile(profile: DetectorProfile, path: Path) -> None:
    """The profile as JSON at ``path`` (atomically)."""
    write_text_atomic(Path(path), json.dumps(profile.to_dict(), indent=1) + "\n")
