"""The onnxruntime detector on graphs built with onnx.helper: Ultralytics YOLOv8 layout with known boxes,
NMS-in-graph and YOLOv5 layouts, letterbox mapping, class-aware NMS, corrupt and incompatible models."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bimkit.errors import InputError
from initcli.detector.runtime import Detector


def constant_model(
    path: Path,
    output: np.ndarray,
    input_shape: tuple = (1, 3, 64, 64),
    metadata: dict[str, str] | None = None,
) -> Path:
    """A graph whose output is ``output`` (plus 0 x the input's mean, so the input is used)."""
    onnx = pytest.importorskip("onnx")
    from onnx import TensorProto, helper

    images = helper.make_tensor_value_info("images", TensorProto.FLOAT, list(input_shape))
    out = helper.make_tensor_value_info("output0", TensorProto.FLOAT, list(output.shape))
    const = helper.make_tensor(
        "table", TensorProto.FLOAT, list(output.shape), output.astype(np.float32).ravel()
    )
    zero = helper.make_tensor("zero", TensorProto.FLOAT, [], [0.0])
    nodes = [
        helper.make_node("ReduceMean", ["images"], ["mean"], keepdims=0),
        helper.make_node("Mul", ["mean", "zero"], ["nothing"]),
        helper.make_node("Add", ["table", "nothing"], ["output0"]),
    ]
    graph = helper.make_graph(nodes, "g", [images], [out], initializer=[const, zero])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    for k, v in (metadata or {}).items():
        helper.set_model_props(model, {**{p.key: p.value for p in model.metadata_props}, k: v})
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return path


def ultralytics_output(boxes_xywh: list[tuple], scores: list[list[float]], n: int = 50) -> np.ndarray:
    nc = len(scores[0])
    out = np.zeros((1, 4 + nc, n), dtype=np.float32)
    for k, (b, s) in enumerate(zip(boxes_xywh, scores, strict=True)):
        out[0, :4, k] = b
        out[0, 4:, k] = s
    return out


def test_ultralytics_layout_known_boxes(tmp_path):
    """[1, 4+nc, N], names in metadata, letterbox 114: boxes come back in original image pixels."""
    out = ultralytics_output(
        [(32, 32, 20, 40), (33, 32, 20, 40), (32, 32, 20, 40), (10, 10, 4, 4)],
        [[0.9, 0.0, 0.0], [0.8, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 0.1]],
    )
    path = constant_model(
        tmp_path / "yolov8.onnx",
        out,
        metadata={"names": "{0: 'door', 1: 'elevator', 2: 'stairs'}", "imgsz": "[64, 64]"},
    )
    det = Detector(path, conf=0.25)
    assert (
        det.layout == "yolov8" and det.names == ["door", "elevator", "stairs"] and det.input_size == (64, 64)
    )
    image = np.zeros((96, 128, 3), np.uint8)  # letterbox: scale 0.5, 8 px grey bars above and below
    found = det.detect(image)
    # the 0.8 door overlaps the 0.9 door (same class): suppressed; the elevator at the same place is kept
    assert [(d.class_name, round(d.score, 2)) for d in found] == [("door", 0.9), ("elevator", 0.7)]
    assert np.allclose(found[0].box, [(32 - 10) * 2, (32 - 20 - 8) * 2, (32 + 10) * 2, (32 + 20 - 8) * 2])


def test_nms_in_graph_layout(tmp_path):
    out = np.zeros((1, 20, 6), dtype=np.float32)
    out[0, 0] = [8, 8, 24, 40, 0.95, 1]
    out[0, 1] = [30, 30, 60, 60, 0.4, 0]
    path = constant_model(tmp_path / "nms.onnx", out, metadata={"names": "{0: 'door', 1: 'lift'}"})
    det = Detector(path, conf=0.25)
    assert det.layout == "nms"
    found = det.detect(np.zeros((64, 64, 3), np.uint8))
    assert [(d.class_name, round(d.score, 2), d.box) for d in found] == [
        ("lift", 0.95, (8.0, 8.0, 24.0, 40.0)),
        ("door", 0.4, (30.0, 30.0, 60.0, 60.0)),
    ]


def test_yolov5_layout_without_names(tmp_path):
    out = np.zeros((1, 30, 7), dtype=np.float32)  # 5 + 2 classes
    out[0, 0] = [32, 32, 10, 10, 0.9, 0.2, 0.8]
    path = constant_model(tmp_path / "v5.onnx", out)
    det = Detector(path, conf=0.25)
    assert det.layout == "yolov5" and det.names == ["class0", "class1"]
    (d,) = det.detect(np.zeros((64, 64, 3), np.uint8))
    assert d.class_name == "class1" and d.score == pytest.approx(0.72)


def test_dynamic_input_uses_metadata_size(tmp_path):
    out = ultralytics_output([(16, 16, 8, 8)], [[0.9]], n=10)
    path = constant_model(
        tmp_path / "dyn.onnx",
        out,
        input_shape=(1, 3, "height", "width"),
        metadata={"names": "{0: 'door'}", "imgsz": "[32, 32]"},
    )
    assert Detector(path).input_size == (32, 32)


def test_bad_models(tmp_path):
    corrupt = tmp_path / "corrupt.onnx"
    corrupt.write_bytes(b"\x08\x07this is not a protobuf model" * 10)
    with pytest.raises(InputError, match="not a usable ONNX model"):
        Detector(corrupt)
    with pytest.raises(InputError, match="no such model file"):
        Detector(tmp_path / "missing.onnx")
    gray = constant_model(
        tmp_path / "gray.onnx", ultralytics_output([(1, 1, 1, 1)], [[1.0]]), input_shape=(1, 1, 64, 64)
    )
    with pytest.raises(InputError, match="1 channels"):
        Detector(gray)
    odd = constant_model(tmp_path / "odd.onnx", np.zeros((1, 2, 3, 4), np.float32))
    with pytest.raises(InputError, match="fits no supported layout|3 dimensions"):
        Detector(odd)
    mismatch = constant_model(
        tmp_path / "mismatch.onnx",
        ultralytics_output([(1, 1, 1, 1)], [[1.0, 0.0]]),
        metadata={"names": "{0: 'door', 1: 'lift', 2: 'stairs'}"},
    )
    with pytest.raises(InputError):
        Detector(mismatch)


def test_without_onnxruntime_a_detector_is_one_line_naming_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    import builtins

    real = builtins.__import__

    def no_onnxruntime(name: str, *args: object, **kwargs: object) -> object:
        if name == "onnxruntime":
            raise ImportError("No module named 'onnxruntime'")
        return real(name, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(builtins, "__import__", no_onnxruntime)
    with pytest.raises(InputError, match=r"default.onnx: the detector runs .* 'bim-init\[detector\]'"):
        Detector("default")
