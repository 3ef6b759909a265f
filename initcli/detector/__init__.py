"""The object detector of paper §3.2.2 / §3.3.1: doors, lifts and staircases in the camera stream.

Modules (torch is imported only by :mod:`model`, :mod:`train` and :mod:`export`):

- :mod:`scene` -- a storey's walls and features as the renderer sees them (``Scene.from_storey``).
- :mod:`look` -- appearance: textures, colours, lighting (fixed for the simulator, random for data).
- :mod:`render` -- the numpy raycaster: ``render_view(scene, pose_xy_yaw, camera) -> View``.
- :mod:`synth` -- synthetic YOLO datasets with domain randomisation, contact sheets.
- :mod:`datasets` -- YOLO (incl. Roboflow-style paths) and COCO readers.
- :mod:`model`, :mod:`train`, :mod:`export` -- the PyTorch network, its training, the ONNX export.
- :mod:`preprocess`, :mod:`layouts`, :mod:`runtime` -- onnxruntime inference: letterbox, output
  layouts (ours, Ultralytics YOLOv8/11, YOLOv5, NMS-in-graph), decoding, class-aware NMS.
- :mod:`metrics`, :mod:`evaluate` -- precision, recall and AP@0.5 per class.
- :mod:`sensor` -- the camera in the loop: render, detect, depth window -> detection-log objects.
- :mod:`cli` -- ``bim-init detector synth|train|export|predict|eval``.

See ``README.md`` in this folder for the commands, the data and what the shipped model can do.
"""

from __future__ import annotations

from pathlib import Path

CLASS_NAMES: tuple[str, ...] = ("door", "lift", "stairs")
MODELS_DIR = Path(__file__).resolve().parent / "models"
DEFAULT_MODEL = MODELS_DIR / "default.onnx"


def resolve_model_path(model: str | Path) -> Path:
    """``default`` -> the model shipped in the package; anything else is a path."""
    if str(model).strip().lower() == "default":
        return DEFAULT_MODEL
    return Path(model)
