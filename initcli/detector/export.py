"""``bim-init detector export``: a training checkpoint -> one self-contained ONNX file.

Static input ``images`` ``[1, 3, H, W]`` (RGB, letterboxed with 114, values / 255), output
``output0`` ``[1, 4 + nc, N]`` (the YOLOv8 layout, see :class:`initcli.detector.model.ExportHead`).
Class names, input size and preprocessing go into ``metadata_props`` -- ``names`` and ``imgsz``
as Ultralytics writes them, plus ``bim_init.preprocess`` and ``bim_init.layout`` -- and the
weights are stored inside the file (no external-data sidecar). The export is checked: the
onnxruntime output must equal PyTorch's within 1e-4 on several inputs (absolute for scores,
relative for box coordinates in pixels: ``np.allclose(ort, torch, rtol=1e-4, atol=1e-4)``).
"""

from __future__ import annotations

import ast
import json
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from bimtools.errors import InputError
from initcli.detector.model import ExportHead
from initcli.detector.preprocess import PAD_VALUE
from initcli.detector.train import load_checkpoint, model_from_checkpoint

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
    net = model_from_checkpoint(ckpt)
    names = [str(n) for n in ckpt["names"]]
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
    onnx.save_model(model, str(out), save_as_external_data=False)
    diff = verify_export(head, out, size) if verify else float("nan")
    if verify and not diff <= atol:
        out.unlink(missing_ok=True)
        raise InputError(f"{out}: onnxruntime output differs from PyTorch by {diff:.2e} (> {atol:.0e})")
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


def _batch_norm_after(calls: list[torch.nn.Module], k: int) -> torch.nn.BatchNorm2d | None:
    """The batch norm the forward pass calls right after ``calls[k]``, if it does."""
    following = calls[k + 1] if k + 1 < len(calls) else None
    return following if isinstance(following, torch.nn.BatchNorm2d) else None


def checkpoint_from_onnx(path: Path) -> dict:
    """A training checkpoint rebuilt from one of our ONNX exports (``train --init default``).

    The export folds each batch norm into its convolution; the rebuilt network gets the folded
    weights and identity batch norms (scale 1, mean 0, variance 1 - eps), which is exact as long as
    batch-norm statistics stay frozen -- fine-tuning from ``--init`` keeps them frozen. Convolutions
    are matched in the order the forward pass calls them, checked by shape.
    """
    import onnx
    import torch
    from onnx import numpy_helper

    from initcli.detector.model import Arch, Detector

    try:
        model = onnx.load(str(path))
    except Exception as exc:  # noqa: BLE001 - any parse problem is a bad input file
        raise InputError(f"{path}: not an ONNX model ({type(exc).__name__})") from None
    meta = {p.key: p.value for p in model.metadata_props}
    if meta.get("author") != "bim-init":
        raise InputError(
            f"{path}: --init needs a bim-init export (this one was made by {meta.get('author')})"
        )
    training = json.loads(meta.get("bim_init.training") or "{}")
    names_map = ast.literal_eval(meta["names"])
    names = [str(names_map[i]) for i in sorted(names_map)]
    arch = Arch.from_dict(training["arch"]) if training.get("arch") else Arch(nc=len(names))
    net = Detector(arch)
    calls: list[torch.nn.Module] = []
    hooks = [
        m.register_forward_hook(lambda mod, _i, _o: calls.append(mod))
        for m in net.modules()
        if isinstance(m, torch.nn.Conv2d | torch.nn.BatchNorm2d)
    ]
    imgsz = int(ast.literal_eval(meta["imgsz"])[0])
    with torch.no_grad():
        net.eval()(torch.zeros(1, 3, imgsz, imgsz))
    for h in hooks:
        h.remove()
    pairs = [  # each convolution with the batch norm called right after it (folded into it on export)
        (m, _batch_norm_after(calls, k)) for k, m in enumerate(calls) if isinstance(m, torch.nn.Conv2d)
    ]
    inits = {i.name: numpy_helper.to_array(i) for i in model.graph.initializer}
    convs = [n for n in model.graph.node if n.op_type == "Conv"]
    if len(convs) != len(pairs):
        raise InputError(f"{path}: {len(convs)} convolutions in the graph, the architecture has {len(pairs)}")
    with torch.no_grad():
        for node, (conv, bn) in zip(convs, pairs, strict=True):
            w = inits.get(node.input[1])
            if w is None or tuple(w.shape) != tuple(conv.weight.shape):
                raise InputError(f"{path}: convolution {node.name} does not fit the architecture")
            conv.weight.copy_(torch.from_numpy(w.copy()))
            b = inits[node.input[2]] if len(node.input) > 2 else np.zeros(w.shape[0], np.float32)
            if bn is not None:
                assert bn.running_mean is not None and bn.running_var is not None  # Detector tracks stats
                bn.weight.fill_(1.0)
                bn.bias.copy_(torch.from_numpy(b.copy()))
                bn.running_mean.zero_()
                bn.running_var.fill_(1.0 - bn.eps)
            elif conv.bias is not None:
                conv.bias.copy_(torch.from_numpy(b.copy()))
            elif np.abs(b).max() > 0:
                raise InputError(
                    f"{path}: convolution {node.name} has a bias the architecture has no place for"
                )
    state = {k: v.detach().clone() for k, v in net.state_dict().items()}
    return {
        "format": "bim-init.detector/1",
        "arch": arch.to_dict(),
        "model": state,
        "raw": state,
        "epoch": 0,
        "step": 0,
        "names": names,
        "imgsz": imgsz,
        "history": [],
        "options": {"init": str(path)},
    }
