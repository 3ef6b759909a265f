"""``bim-init detector export``: a training checkpoint -> one self-contained ONNX file.

Static input ``images`` ``[1, 3, H, W]`` (RGB, letterboxed with 114, values / 255), output
``output0`` ``[1, 4 + nc, N]`` (the YOLOv8 layout, see :class:`initcli.detector.training.model.ExportHead`).
Class names, input size and preprocessing go into ``metadata_props`` -- ``names`` and ``imgsz``
as Ultralytics writes them, plus ``bim_init.preprocess`` and ``bim_init.layout`` -- and the
weights are stored inside the file (no external-data sidecar). The export is checked: the
onnxruntime output must equal PyTorch's within 1e-4 on several inputs (absolute for scores,
relative for box coordinates in pixels: ``np.allclose(ort, torch, rtol=1e-4, atol=1e-4)``).
"""

from __future__ import annotations

import json
import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from bimkit.errors import InputError
from initcli.detector.preprocess import PAD_VALUE
from initcli.detector.training.checkpoint import load_checkpoint, model_from_checkpoint
from initcli.detector.training.model import ExportHead

__all__ = ["ExportReport", "OPSET", "export_onnx", "model_metadata", "package_version", "verify_export"]

OPSET = 17


def package_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("bim-init")
    except PackageNotFoundError:
        return "0.1.0"


@dataclass
class ExportReport:
    path: Path
    imgsz: int
    names: list[str]
    max_abs_diff: float
    bytes: int
    metadata: dict[str, str]


def model_metadata(names: list[str], imgsz: int, ckpt: dict) -> dict[str, str]:
    history = ckpt.get("history") or []
    last = history[-1] if history else {}
    opts = ckpt.get("options") or {}
    training = {
        "epochs": ckpt.get("epoch"),
        "data": opts.get("data"),
        "imgsz": ckpt.get("imgsz"),
        "arch": ckpt.get("arch"),
        "val_metrics": last.get("metrics") or None,
    }
    return {
        "names": repr({i: n for i, n in enumerate(names)}),
        "imgsz": repr([imgsz, imgsz]),
        "stride": "32",
        "task": "detect",
        "batch": "1",
        "author": "bim-init",
        "version": f"bim-init {package_version()}",
        "description": "bim-init compact anchor-free detector (TTFNet-style heatmap + box distances)",
        "bim_init.layout": "yolov8",
        "bim_init.preprocess": json.dumps(
            {
                "letterbox": True,
                "pad_value": PAD_VALUE,
                "color": "RGB",
                "scale": 1.0 / 255.0,
                "layout": "NCHW",
            }
        ),
        "bim_init.training": json.dumps(training),
    }


def export_onnx(
    checkpoint: Path, out: Path, imgsz: int | None = None, atol: float = 1e-4, verify: bool = True
) -> ExportReport:
    """Export, embed metadata, verify against PyTorch; raises :class:`InputError` on failure."""
    import onnx

    ckpt = load_checkpoint(checkpoint)
    net = model_from_checkpoint(ckpt, checkpoint)
    given = ckpt.get("names")
    if not isinstance(given, list | tuple) or not all(isinstance(n, str) and n.strip() for n in given):
        raise InputError(f"{checkpoint}: no class names (a 'names' list of strings, as train writes)")
    names = [str(n) for n in given]
    if len(names) != net.arch.nc:
        raise InputError(f"{checkpoint}: {len(names)} class names for a network of {net.arch.nc} classes")
    size = int(imgsz or ckpt.get("imgsz") or 320)
    if size % 32:
        raise InputError(f"--imgsz: must be a multiple of 32, got {size}")
    head = ExportHead(net, (size, size)).eval()
    example = torch.rand(1, 3, size, size, generator=torch.Generator().manual_seed(0))
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        raw = Path(tmp) / "raw.onnx"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            torch.onnx.export(
                head,
                (example,),
                str(raw),
                dynamo=False,
                opset_version=OPSET,
                input_names=["images"],
                output_names=["output0"],
                do_constant_folding=True,
            )
        model = onnx.load(str(raw), load_external_data=True)
    meta = model_metadata(names, size, ckpt)
    del model.metadata_props[:]
    for k, v in meta.items():
        entry = model.metadata_props.add()
        entry.key, entry.value = k, v
    model.producer_name = "bim-init"
    model.producer_version = package_version()
    onnx.checker.check_model(model)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".onnx", dir=out.parent)
    os.close(fd)
    staged = Path(tmp_name)  # written and verified beside ``out``, then moved there: never half a model
    try:
        onnx.save_model(model, str(staged), save_as_external_data=False)
        diff = verify_export(head, staged, size) if verify else float("nan")
        if verify and not diff <= atol:
            raise InputError(f"{out}: onnxruntime output differs from PyTorch by {diff:.2e} (> {atol:.0e})")
        os.replace(staged, out)
    finally:
        staged.unlink(missing_ok=True)
    return ExportReport(out, size, names, diff, out.stat().st_size, meta)


@torch.no_grad()
def verify_export(head: ExportHead, path: Path, size: int, trials: int = 3) -> float:
    """Largest difference between onnxruntime and PyTorch outputs over a few inputs, as
    ``|ort - torch| / (1 + |torch|)``: absolute for the scores (0-1), relative for box pixels."""
    import onnxruntime as ort

    sess = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    gen = torch.Generator().manual_seed(1)
    worst = 0.0
    for k in range(trials):
        x = (
            torch.rand(1, 3, size, size, generator=gen)
            if k
            else torch.full((1, 3, size, size), PAD_VALUE / 255.0)
        )
        ref = head(x).numpy()
        got = sess.run(None, {"images": x.numpy()})[0]
        if got.shape != ref.shape:
            raise InputError(
                f"{path}: onnxruntime output shape {got.shape} differs from PyTorch's {ref.shape}"
            )
        # np.allclose(got, ref, rtol=1e-4, atol=1e-4) <=> this normalised difference <= 1e-4
        worst = max(worst, float(np.max(np.abs(got - ref) / (1.0 + np.abs(ref)))))
    return worst


# --- back from ONNX: the starting point of `train --init default` -----------------------------------
