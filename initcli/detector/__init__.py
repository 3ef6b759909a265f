"""The object detector of paper §3.2.2 / §3.3.1: doors, lifts and staircases in the camera stream.

Three parts, each importable without the next:

- this package, the runtime (onnxruntime, the ``[detector]`` extra; OpenCV and numpy):
  :mod:`.preprocess` (letterbox), :mod:`.layouts` (output layouts: ours, Ultralytics YOLOv8/11,
  YOLOv5, NMS-in-graph; decoding, class-aware NMS), :mod:`.runtime` (the ONNX detector),
  :mod:`.datasets` (YOLO, Roboflow-style and COCO readers), :mod:`.metrics` and :mod:`.evaluate`
  (precision, recall, AP@0.5 per class);
- :mod:`initcli.detector.synth`, rendering: :mod:`~initcli.detector.synth.scene` (a storey as the
  renderer sees it), :mod:`~initcli.detector.synth.look` (textures, colours, lighting),
  :mod:`~initcli.detector.synth.render` (the numpy raycaster; its colours in
  :mod:`~initcli.detector.synth.paint`) and
  :mod:`~initcli.detector.synth.dataset` (synthetic YOLO datasets with domain randomisation);
- :mod:`initcli.detector.training`, PyTorch (the ``[train]`` extra): the network
  (:mod:`~initcli.detector.training.model`), augmentation, checkpoints, training and the ONNX export.

The command face is :mod:`initcli.cli.detector`; ``README.md`` in this folder has the commands,
the data and what the shipped model can do.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

__all__ = [
    "CLASS_NAMES",
    "DEFAULT_MODEL",
    "MODELS_DIR",
    "RUNTIME_AVAILABLE",
    "RUNTIME_MISSING",
    "resolve_model_path",
]

CLASS_NAMES: tuple[str, ...] = ("door", "lift", "stairs")
# The detector's own score threshold: boxes the network scores lower are dropped where it runs (the
# ONNX runtime, bag2log, the reported precision and recall). The detection filter of the match
# (``detector.score_threshold`` / ``--score-threshold``, 0.5) filters the logged boxes again.
DETECTOR_CONFIDENCE = 0.25
MODELS_DIR = Path(__file__).resolve().parent / "models"
DEFAULT_MODEL = MODELS_DIR / "default.onnx"
# onnxruntime, which runs the network, is the [detector] extra: the package runs without it, on
# simulated detections and on logs that carry their detections.
RUNTIME_AVAILABLE = importlib.util.find_spec("onnxruntime") is not None
RUNTIME_MISSING = (
    "runs the detection network with onnxruntime, which is not installed: pip install 'bim-init[detector]'"
)


def resolve_model_path(model: str | Path) -> Path:
    """``default`` -> the model shipped in the package; anything else is a path."""
    if str(model).strip().lower() == "default":
        return DEFAULT_MODEL
    return Path(model)
