"""Run a detection ONNX model with onnxruntime (no torch): letterbox, decode, class-aware NMS.

Reads our own exports and the layouts users most often bring (see :mod:`initcli.detector.layouts`):
Ultralytics YOLOv8 / YOLO11 (``[1, 4+nc, N]``, class names in the ``names`` metadata), YOLOv5
(``[1, N, 5+nc]``) and graphs with NMS inside (``[1, N, 6]``). The layout is recognised from
the output's shape (found by one run on a blank image when the model is loaded) and the metadata.
A file that is missing, corrupt or not a detector gives :class:`InputError` with one line.
"""

from __future__ import annotations

import ast
import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np

from bimkit.documents import check_regular
from bimkit.errors import InputError
from bimkit.limits import MAX_MODEL_BYTES
from initcli.detector import DEFAULT_MODEL, DETECTOR_CONFIDENCE, RUNTIME_MISSING, resolve_model_path
from initcli.detector.layouts import LayoutError, decode, infer_layout, nms
from initcli.detector.preprocess import PAD_VALUE, Letterbox, letterbox

if TYPE_CHECKING:
    import onnxruntime as ort

__all__ = ["DEFAULT_IMGSZ", "Detection", "Detector", "Preprocess", "session_options"]

DEFAULT_IMGSZ = 640  # Ultralytics' default when the input size is dynamic and not in the metadata


@dataclass(frozen=True)
class Detection:
    class_name: str
    score: float
    box: tuple[float, float, float, float]  # x1 y1 x2 y2 in image pixels
    class_id: int = -1


@dataclass(frozen=True)
class Preprocess:
    letterbox: bool = True
    pad_value: int = PAD_VALUE
    rgb: bool = True
    scale: float = 1.0 / 255.0


def _parse_names(raw: str | None) -> list[str] | None:
    if not raw:
        return None
    try:
        value = ast.literal_eval(raw)
    except (ValueError, SyntaxError):
        try:
            value = json.loads(raw)
        except json.JSONDecodeError:
            return None
    if isinstance(value, dict):
        try:
            return [str(value[k]) for k in sorted(value, key=lambda k: int(k))]
        except (TypeError, ValueError):
            return None
    if isinstance(value, list | tuple):
        return [str(v) for v in value]
    return None


def _parse_imgsz(raw: str | None) -> tuple[int, int] | None:
    if not raw:
        return None
    try:
        value = ast.literal_eval(raw)
    except (ValueError, SyntaxError):
        return None
    if isinstance(value, int):
        return value, value
    if isinstance(value, list | tuple) and len(value) == 2:
        return int(value[0]), int(value[1])
    return None


def _parse_preprocess(raw: str | None) -> Preprocess:
    if not raw:
        return Preprocess()
    try:
        doc = json.loads(raw)
    except json.JSONDecodeError:
        return Preprocess()
    return Preprocess(
        letterbox=bool(doc.get("letterbox", True)),
        pad_value=int(doc.get("pad_value", PAD_VALUE)),
        rgb=str(doc.get("color", "RGB")).upper() == "RGB",
        scale=float(doc.get("scale", 1.0 / 255.0)),
    )


def _first_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text[:200] + ("..." if len(text) > 200 else "")


def session_options(threads: int = 2) -> ort.SessionOptions:
    """onnxruntime settings for a robot that shares its cores: fixed threads, no idle spinning."""
    import onnxruntime as ort

    so = ort.SessionOptions()
    so.intra_op_num_threads = max(1, int(threads))
    so.inter_op_num_threads = 1
    so.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    so.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    so.add_session_config_entry("session.intra_op.allow_spinning", "0")
    so.add_session_config_entry("session.inter_op.allow_spinning", "0")
    so.log_severity_level = 3
    return so


class Detector:
    """An ONNX detector: ``Detector("default").detect(image_bgr) -> [Detection, ...]``."""

    def __init__(
        self,
        model: str | Path = "default",
        conf: float = DETECTOR_CONFIDENCE,
        iou: float = 0.5,
        max_det: int = 100,
        threads: int = 2,
        names: list[str] | None = None,
        providers: list[str] | None = None,
    ) -> None:
        path = resolve_model_path(model)
        self.path = path
        if not path.exists():
            if path == DEFAULT_MODEL:
                raise InputError(f"{path}: the default model is missing from the installation")
            raise InputError(f"{path}: no such model file")
        if path.is_dir():
            raise InputError(f"{path}: is a folder, expected an .onnx model file")
        check_regular(path, "an ONNX model", MAX_MODEL_BYTES)
        self.conf, self.iou, self.max_det = conf, iou, max_det
        try:
            import onnxruntime as ort
        except ImportError:
            raise InputError(f"{path}: the detector {RUNTIME_MISSING}") from None
        try:
            self.session = ort.InferenceSession(
                str(path), session_options(threads), providers=providers or ["CPUExecutionProvider"]
            )
        except Exception as exc:  # noqa: BLE001 - onnxruntime raises several types for a bad file
            raise InputError(f"{path}: not a usable ONNX model ({_first_line(exc)})") from None
        meta = self.session.get_modelmeta().custom_metadata_map or {}
        self.metadata: dict[str, str] = dict(meta)
        inputs = self.session.get_inputs()
        if len(inputs) != 1 or len(inputs[0].shape) != 4:
            shapes = [list(i.shape) for i in inputs]
            raise InputError(f"{path}: expected one image input [1, 3, H, W], the model has {shapes}")
        inp = inputs[0]
        self.input_name = inp.name
        if inp.type not in ("tensor(float)", "tensor(float16)"):
            raise InputError(f"{path}: input {inp.name!r} is {inp.type}; expected float32 or float16")
        self.input_dtype = np.float16 if inp.type == "tensor(float16)" else np.float32
        c = inp.shape[1]
        if isinstance(c, int) and c != 3:
            raise InputError(f"{path}: input {inp.name!r} has {c} channels; expected [1, 3, H, W]")
        h, w = inp.shape[2], inp.shape[3]
        meta_size = _parse_imgsz(meta.get("imgsz"))
        if not (isinstance(h, int) and isinstance(w, int) and h > 0 and w > 0):
            h, w = meta_size or (DEFAULT_IMGSZ, DEFAULT_IMGSZ)
        self.input_size = (int(h), int(w))
        self.preprocess = _parse_preprocess(meta.get("bim_init.preprocess"))
        meta_names = names or _parse_names(meta.get("names"))
        try:
            out = self._run(
                np.full(
                    (1, 3, *self.input_size),
                    self.preprocess.pad_value * self.preprocess.scale,
                    dtype=self.input_dtype,
                )
            )
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001
            raise InputError(
                f"{path}: the model does not run on a {list(self.input_size)} image ({_first_line(exc)})"
            ) from None
        try:
            self.layout, nc = infer_layout(
                tuple(out.shape), len(meta_names) if meta_names else None, meta.get("bim_init.layout")
            )
        except LayoutError as exc:
            raise InputError(f"{path}: {exc}") from None
        if meta_names is not None and self.layout != "nms" and len(meta_names) != nc:
            raise InputError(f"{path}: the metadata names {len(meta_names)} classes but the output has {nc}")
        self.names = meta_names or [f"class{i}" for i in range(nc)]

    def _run(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(self.session.run(None, {self.input_name: x})[0])

    def prepare(self, image_bgr: np.ndarray) -> tuple[np.ndarray, Letterbox]:
        """The network input for a BGR image and the letterbox used."""
        if image_bgr is None or image_bgr.ndim != 3 or image_bgr.shape[2] != 3:
            raise InputError("detector: expected an H x W x 3 BGR image")
        pp = self.preprocess
        img = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2RGB) if pp.rgb else image_bgr
        if pp.letterbox:
            img, lb = letterbox(img, self.input_size, pp.pad_value)
        else:
            h, w = img.shape[:2]
            img = cv2.resize(img, (self.input_size[1], self.input_size[0]), interpolation=cv2.INTER_LINEAR)
            lb = Letterbox(self.input_size[1] / w, 0.0, 0.0, self.input_size[0] / h)
        x = np.ascontiguousarray(img.transpose(2, 0, 1)[None], dtype=np.float32)
        x *= np.float32(pp.scale)
        return x.astype(self.input_dtype, copy=False), lb

    def detect(self, image_bgr: np.ndarray, conf: float | None = None) -> list[Detection]:
        """Detections in image pixels, best first."""
        x, lb = self.prepare(image_bgr)
        out = self._run(x)
        boxes, scores, classes = decode(out, self.layout, self.conf if conf is None else conf)
        if self.layout != "nms":
            keep = nms(boxes, scores, classes, self.iou, self.max_det)
            boxes, scores, classes = boxes[keep], scores[keep], classes[keep]
        else:
            order = np.argsort(-scores)[: self.max_det]
            boxes, scores, classes = boxes[order], scores[order], classes[order]
        boxes = lb.to_image(boxes)
        h, w = image_bgr.shape[:2]
        boxes[:, [0, 2]] = boxes[:, [0, 2]].clip(0, w)
        boxes[:, [1, 3]] = boxes[:, [1, 3]].clip(0, h)
        out_list = []
        for b, s, c in zip(boxes, scores, classes, strict=True):
            ci = int(c)
            name = self.names[ci] if 0 <= ci < len(self.names) else f"class{ci}"
            out_list.append(
                Detection(name, float(s), (float(b[0]), float(b[1]), float(b[2]), float(b[3])), ci)
            )
        return out_list
