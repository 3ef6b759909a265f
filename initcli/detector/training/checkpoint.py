"""Training checkpoints: saved and loaded atomically, the network rebuilt from one, and a checkpoint
rebuilt from one of our ONNX exports (``train --init default``)."""

from __future__ import annotations

import ast
import json
import os
from pathlib import Path

import numpy as np
import torch

from bimkit.documents import check_regular
from bimkit.errors import InputError
from bimkit.limits import MAX_MODEL_BYTES
from initcli.detector import DEFAULT_MODEL
from initcli.detector.training.model import Arch, Detector, upgrade_state_dict

__all__ = ["checkpoint_from_onnx", "load_checkpoint", "load_init", "model_from_checkpoint", "save_checkpoint"]


def save_checkpoint(path: Path, state: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    torch.save(state, tmp)
    os.replace(tmp, path)


def load_checkpoint(path: Path) -> dict:
    if not Path(path).exists():
        raise InputError(f"{path}: no such checkpoint")
    check_regular(Path(path), "a bim-init checkpoint (.pt)", MAX_MODEL_BYTES)
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:  # noqa: BLE001 - any unpickling problem is a bad input file
        raise InputError(f"{path}: not a bim-init checkpoint ({type(exc).__name__})") from None
    if not isinstance(ckpt, dict) or "model" not in ckpt or "arch" not in ckpt:
        raise InputError(f"{path}: not a bim-init checkpoint (no model/arch)")
    model_from_checkpoint(ckpt, path)  # every weight there and of the right shape, before any work
    return ckpt


def _listed(names: list[str]) -> str:
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def model_from_checkpoint(ckpt: dict, source: Path | str = "the checkpoint") -> Detector:
    """The network a checkpoint holds; :class:`InputError` naming ``source`` where its architecture
    cannot be built or a weight is missing, unexpected or of another shape."""
    try:
        net = Detector(Arch.from_dict(ckpt["arch"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{source}: its arch cannot be built ({type(exc).__name__}: {exc})") from None
    state = ckpt["model"]
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise InputError(f"{source}: its model is not a table of weights")
    state = upgrade_state_dict(state)
    own = net.state_dict()
    missing = [k for k in own if k not in state]
    unexpected = [k for k in state if k not in own]
    reshaped = [k for k in own if k in state and tuple(state[k].shape) != tuple(own[k].shape)]
    for what, names in (
        ("missing", missing),
        ("not of this network", unexpected),
        ("of another shape", reshaped),
    ):
        if names:
            raise InputError(f"{source}: weights {what}: {_listed(names)}")
    net.load_state_dict(state)
    return net.eval()


def load_init(init: str) -> dict:
    """``--init``: 'default' (the shipped ONNX model, rebuilt as a checkpoint), a ``.onnx`` export of ours
    or a ``.pt`` checkpoint."""
    if init == "default":
        return checkpoint_from_onnx(DEFAULT_MODEL)
    path = Path(init)
    if path.suffix.lower() == ".onnx":
        if not path.exists():
            raise InputError(f"{path}: no such model")
        return checkpoint_from_onnx(path)
    return load_checkpoint(path)


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
    from onnx import numpy_helper

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
