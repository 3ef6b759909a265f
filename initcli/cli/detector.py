"""``bim-init detector``: synth, train, export, predict, eval, calibrate.

Heavy imports (torch, onnxruntime) happen inside the commands, so ``bim-init --help`` and the
onnxruntime commands work without the ``[train]`` extra. Bad input: one line on stderr, exit 2.
"""

from __future__ import annotations

import json
import os
import sys
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from bimkit.cli import HELP, error_line, number_option
from bimkit.errors import EXIT_BAD_INPUT, InputError
from bimkit.outputs import OutputFile, OutputFolder, check_outputs
from bimkit.ownership import json_of_format, starts_with_marker
from initcli.cli import PROG
from initcli.cli.progress import TrainingProgress, metrics_table
from initcli.detector import DETECTOR_CONFIDENCE

if TYPE_CHECKING:
    from initcli.detector.runtime import Detector

__all__ = [
    "MODEL_HELP",
    "TORCH_MISSING",
    "calibrate",
    "detector_app",
    "evaluate",
    "export",
    "predict",
    "synth",
    "train",
]

detector_app = typer.Typer(
    name="detector",
    help="The object detector (paper §3.2.2): synthetic data from the BIM, training, ONNX export, inference.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    **HELP,
)

MODEL_HELP = "An .onnx model; 'default' is the model shipped in the package."
TORCH_MISSING = "needs PyTorch, the [train] extra: pip install 'bim-init[train]'"


def _fail(message: object) -> typer.Exit:
    typer.echo(error_line(PROG, message), err=True)
    return typer.Exit(EXIT_BAD_INPUT)


def _console() -> Console:
    return Console(width=None if sys.stdout.isatty() else 120, soft_wrap=False)


def _parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InputError(f"--size: expected WxH such as 320x240, got {text!r}") from None
    if not (16 <= w <= 4096 and 16 <= h <= 4096):
        raise InputError(f"--size: width and height must be 16-4096 pixels, got {text!r}")
    return w, h


def _require_torch(command: str) -> None:
    # Idle OpenMP threads sleep instead of spinning: on a machine whose cores are shared (a robot, CI),
    # spinning threads made training several times slower. Only effective before torch is imported.
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    try:
        import torch  # noqa: F401
    except ImportError:
        raise InputError(f"bim-init detector {command} {TORCH_MISSING}") from None


# --- synth -----------------------------------------------------------------------------------------

# The options of synth and train that take more than a line (typer reads these Annotated types).
_SynthSites = Annotated[
    list[Path],
    typer.Option("--site", metavar="SITE", help="bim-extract OUTDIR (repeat for several sites)."),
]
_SynthImages = Annotated[
    int,
    typer.Option(
        "--images",
        callback=number_option(PROG, minimum=1, maximum=1_000_000),
        metavar="N",
        help="Images to render.",
    ),
]
_SynthSeed = Annotated[
    int,
    typer.Option(
        "--seed",
        callback=number_option(PROG, minimum=0, maximum=2**32 - 1),
        metavar="S",
        help="Random seed (image i depends on S, i).",
    ),
]
_ValFraction = Annotated[
    float,
    typer.Option(
        "--val-fraction",
        callback=number_option(PROG, minimum=0, maximum=1),
        metavar="F",
        help="Share of images in the val split (1: a test set, every image in val).",
    ),
]
_Preview = Annotated[
    Path | None,
    typer.Option("--preview", metavar="FILE.png", help="Write a contact sheet of labelled images."),
]
_SynthWorkers = Annotated[
    int,
    typer.Option(
        "--workers",
        callback=number_option(PROG, minimum=0, maximum=64),
        metavar="N",
        help="Processes; 0 = one per core (max 2).",
    ),
]
_ShuffleClasses = Annotated[
    float,
    typer.Option(
        "--shuffle-classes",
        callback=number_option(PROG, minimum=0, maximum=1),
        metavar="P",
        help="Draw each feature as a random class with this chance (training data; 0 for test sets).",
    ),
]


@detector_app.command()
def synth(
    site: _SynthSites,
    out: Annotated[Path, typer.Option("--out", metavar="DATASET", help="Dataset folder to write.")],
    images: _SynthImages = 500,
    size: Annotated[str, typer.Option("--size", metavar="WxH", help="Image size in pixels.")] = "320x240",
    seed: _SynthSeed = 0,
    val_fraction: _ValFraction = 0.1,
    preview: _Preview = None,
    workers: _SynthWorkers = 0,
    depth: Annotated[
        bool, typer.Option("--depth/--no-depth", help="Also write 16-bit depth PNGs (mm).")
    ] = True,
    shuffle_classes: _ShuffleClasses = 0.0,
) -> None:
    """Render a YOLO dataset (RGB, depth, labels) from site models with domain randomisation."""
    from bimkit.atomic import staged_directory
    from initcli.cli.progress import count_bar
    from initcli.detector.synth.dataset import (
        SYNTH_MARKERS,
        SYNTH_WRITES,
        SynthOptions,
        dataset_preview,
        write_dataset,
    )

    try:
        check_outputs(  # into any folder: the files of others are kept, never written over
            site,
            [
                OutputFolder(out, "--out", SYNTH_MARKERS, SYNTH_WRITES),
                None if preview is None else OutputFile(preview, "--preview", (".png", ".jpg", ".jpeg")),
            ],
            force=True,
        )
        w, h = _parse_size(size)
        opts = SynthOptions(
            images=images,
            width=w,
            height=h,
            seed=seed,
            val_fraction=val_fraction,
            workers=workers,
            depth=depth,
            shuffle_classes=shuffle_classes,
            sites=[str(s) for s in site],
        )
        with count_bar("rendering") as bar, staged_directory(out, SYNTH_MARKERS) as stage:
            task = bar.add_task("rendering", total=images)
            doc = write_dataset(
                site,
                stage,
                opts,
                progress=lambda n: bar.advance(task, n),
                warn=lambda m: typer.echo(f"bim-init: warning: {m}", err=True),
                final=out,
            )
        if preview is not None:
            dataset_preview(out, preview)
    except InputError as exc:
        raise _fail(str(exc)) from None
    inst = doc["instances"]
    typer.echo(
        f"wrote {out}: {doc['images']['train']} train + {doc['images']['val']} val images "
        f"({doc['background_images']} without features)"
    )
    for split in ("train", "val"):
        typer.echo(f"  {split}: " + ", ".join(f"{k} {v}" for k, v in inst[split].items()))
    typer.echo(f"  data.yaml: {out / 'data.yaml'}")
    if preview is not None:
        typer.echo(f"  preview: {preview}")


# --- train -----------------------------------------------------------------------------------------

_TrainData = Annotated[
    Path, typer.Option("--data", metavar="data.yaml|COCO.json", help="YOLO data.yaml or COCO json.")
]
_Epochs = Annotated[
    int, typer.Option("--epochs", callback=number_option(PROG, minimum=1, maximum=10_000), metavar="N")
]
_TrainImgsz = Annotated[
    int,
    typer.Option(
        "--imgsz",
        callback=number_option(PROG, minimum=32, maximum=2048),
        metavar="PX",
        help="Square input size, a multiple of 32.",
    ),
]
_TrainOut = Annotated[
    Path, typer.Option("--out", metavar="model.pt", help="Checkpoint written after every epoch.")
]
_Batch = Annotated[
    int, typer.Option("--batch", callback=number_option(PROG, minimum=1, maximum=1024), metavar="N")
]
_LearningRate = Annotated[
    float,
    typer.Option(
        "--lr",
        callback=number_option(PROG, above=0, maximum=1),
        metavar="LR",
        help="AdamW learning rate.",
    ),
]
_Device = Annotated[str, typer.Option("--device", metavar="auto|cpu|cuda", help="auto: a GPU when present.")]
_TrainWorkers = Annotated[
    int,
    typer.Option(
        "--workers",
        callback=number_option(PROG, minimum=-1, maximum=64),
        metavar="N",
        help="Data loader processes; -1: auto.",
    ),
]
_TimeLimit = Annotated[
    float,
    typer.Option("--time-limit", metavar="MIN", help="Stop after this many minutes (schedule follows time)."),
]
_ValMax = Annotated[
    int,
    typer.Option(
        "--val-max",
        callback=number_option(PROG, minimum=0, maximum=10_000_000),
        metavar="N",
        help="Validate on at most N images.",
    ),
]
_TrainSeed = Annotated[
    int, typer.Option("--seed", callback=number_option(PROG, minimum=0, maximum=2**32 - 1), metavar="S")
]
_Init = Annotated[
    str | None,
    typer.Option(
        "--init",
        metavar="default|model.pt",
        help="Fine-tune: start from the shipped model ('default') or this checkpoint.",
    ),
]
_FreezeBackbone = Annotated[
    bool, typer.Option("--freeze-backbone", help="Train only the neck and heads (small datasets).")
]
_Backbone = Annotated[
    str,
    typer.Option(
        "--backbone",
        metavar="efficientnet_lite0|residual",
        help="A new model's backbone: ImageNet-pretrained lite0, or the small residual one (scratch).",
    ),
]


@detector_app.command()
def train(
    data: _TrainData,
    epochs: _Epochs = 30,
    imgsz: _TrainImgsz = 320,
    out: _TrainOut = Path("model.pt"),
    resume: Annotated[bool, typer.Option("--resume", help="Continue the checkpoint at --out.")] = False,
    batch: _Batch = 16,
    lr: _LearningRate = 2e-3,
    device: _Device = "auto",
    workers: _TrainWorkers = -1,
    time_limit: _TimeLimit = 0.0,
    val_max: _ValMax = 500,
    seed: _TrainSeed = 0,
    init: _Init = None,
    freeze_backbone: _FreezeBackbone = False,
    backbone: _Backbone = "efficientnet_lite0",
) -> None:
    """Train the detector; validates precision, recall and AP@0.5 per class each epoch."""
    try:
        inputs = [data, None if init in (None, "default") else Path(init)]
        outputs = [OutputFile(out, "--out"), OutputFile(out.with_suffix(".csv"), "--out (its history .csv)")]
        check_outputs(inputs, outputs)  # --resume reads --out too: the tool's own checkpoint
        _require_torch("train")
    except InputError as exc:
        raise _fail(str(exc)) from None
    from initcli.detector.training.train import TrainOptions
    from initcli.detector.training.train import train as run_training

    console = _console()
    opts = TrainOptions(
        data=data,
        epochs=epochs,
        imgsz=imgsz,
        batch=batch,
        lr=lr,
        out=out,
        resume=resume,
        device=device,
        workers=workers,
        time_limit=time_limit,
        val_max=val_max,
        seed=seed,
        init=init,
        freeze_backbone=freeze_backbone,
        backbone=backbone,
    )
    display = TrainingProgress(console, epochs)
    try:
        with display.progress:
            run_training(opts, display.on_event)
    except InputError as exc:
        raise _fail(str(exc)) from None
    console.print(
        f"wrote {out} (history in {out.with_suffix('.csv')}); next: bim-init detector export {out} "
        f"-o {out.with_suffix('.onnx')}"
    )


# --- export ----------------------------------------------------------------------------------------


@detector_app.command()
def export(
    model: Annotated[Path, typer.Argument(metavar="MODEL.pt", help="A checkpoint written by train.")],
    out: Annotated[Path | None, typer.Option("-o", "--out", metavar="model.onnx")] = None,
    imgsz: Annotated[
        int | None,
        typer.Option(
            "--imgsz",
            callback=number_option(PROG, minimum=32, maximum=2048),
            metavar="PX",
            help="Input size (default: training size).",
        ),
    ] = None,
) -> None:
    """Export a single-file ONNX model (static 1x3xHxW input, metadata) and verify it against PyTorch."""
    target = out or model.with_suffix(".onnx")
    try:
        onnx_out = OutputFile(target, "-o/--out", (".onnx",), starts_with_marker(b"bim-init"), "model")
        check_outputs([model], [onnx_out])  # an existing model: ours only (its producer_name)
        _require_torch("export")
        try:
            import onnx  # noqa: F401
        except ImportError:
            raise InputError(
                "bim-init detector export needs the onnx package: pip install 'bim-init[train]'"
            ) from None
        from initcli.detector.training.export import export_onnx

        report = export_onnx(model, target, imgsz)
    except InputError as exc:
        raise _fail(str(exc)) from None
    typer.echo(
        f"wrote {report.path} ({report.bytes / 1e6:.1f} MB): input [1, 3, {report.imgsz}, {report.imgsz}], "
        f"classes {report.names}; onnxruntime matches PyTorch within {report.max_abs_diff:.1e}"
    )


# --- predict / eval --------------------------------------------------------------------------------


def _images(paths: list[Path]) -> list[Path]:
    from initcli.detector.datasets import IMAGE_SUFFIXES

    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            out += sorted(q for q in p.rglob("*") if q.suffix.lower() in IMAGE_SUFFIXES)
        elif p.exists():
            out.append(p)
        else:
            raise InputError(f"{p}: no such image")
    if not out:
        raise InputError("no images given")
    return out


_Conf = Annotated[
    float,
    typer.Option(
        "--conf", callback=number_option(PROG, minimum=0, maximum=1), metavar="S", help="Score threshold."
    ),
]
_Iou = Annotated[
    float,
    typer.Option(
        "--iou", callback=number_option(PROG, minimum=0, maximum=1), metavar="T", help="NMS IoU threshold."
    ),
]
_Threads = Annotated[
    int,
    typer.Option(
        "--threads",
        callback=number_option(PROG, minimum=1, maximum=256),
        metavar="N",
        help="onnxruntime intra-op threads.",
    ),
]
_EvalData = Annotated[
    Path, typer.Option("--data", metavar="data.yaml|COCO.json", help="Dataset with labels.")
]
_Split = Annotated[str, typer.Option("--split", metavar="val|train", help="Which split to evaluate.")]
_MaxImages = Annotated[
    int,
    typer.Option(
        "--max-images",
        callback=number_option(PROG, minimum=0, maximum=10_000_000),
        metavar="N",
        help="0 = all.",
    ),
]


@detector_app.command()
def predict(
    model: Annotated[str, typer.Argument(metavar="MODEL.onnx", help=MODEL_HELP)],
    images: Annotated[list[Path], typer.Argument(metavar="IMAGE...", help="Images or folders of images.")],
    out: Annotated[
        Path | None, typer.Option("--out", metavar="DIR", help="Write the images with boxes here.")
    ] = None,
    conf: _Conf = DETECTOR_CONFIDENCE,
    iou: _Iou = 0.5,
    threads: _Threads = 2,
    json_out: Annotated[bool, typer.Option("--json", help="One JSON line per image.")] = False,
) -> None:
    """Detect doors, lifts and stairs in images; print the detections, optionally draw them."""
    from bimkit.atomic import staged_directory
    from initcli.detector.runtime import Detector

    try:
        files = _images(images)
        drawn_names = tuple(sorted({f.stem + ".jpg" for f in files}))
        check_outputs(  # a folder of drawn images: into any folder, never over a file of someone else's
            [*images, None if model == "default" else Path(model)],
            [None if out is None else OutputFolder(out, "--out", (), drawn_names)],
            force=True,
        )
        det = Detector(model, conf=conf, iou=iou, threads=threads)
        with staged_directory(out) if out is not None else nullcontext(None) as stage:
            _predict_all(det, files, stage, json_out)
    except InputError as exc:
        raise _fail(str(exc)) from None


def _predict_all(det: Detector, files: list[Path], stage: Path | None, json_out: bool) -> None:
    """Detect in each image; print the detections, and draw them into ``stage`` when given."""
    import cv2

    from initcli.detector.synth.dataset import draw_boxes
    from initcli.io.images import read_image

    for f in files:
        img = read_image(f)
        found = det.detect(img)
        if json_out:
            typer.echo(
                json.dumps(
                    {
                        "image": str(f),
                        "detections": [
                            {
                                "class": d.class_name,
                                "score": round(d.score, 4),
                                "bbox": [round(v, 1) for v in d.box],
                            }
                            for d in found
                        ],
                    }
                )
            )
        else:
            typer.echo(f"{f}: {len(found)} detection{'s' if len(found) != 1 else ''}")
            for d in found:
                b = ", ".join(f"{v:.0f}" for v in d.box)
                typer.echo(f"  {d.class_name:<8} {d.score:.2f}  [{b}]")
        if stage is not None:
            drawn = draw_boxes(
                img, [(d.class_id, d.box, f"{d.class_name} {d.score:.2f}") for d in found], thickness=2
            )
            target = stage / (f.stem + ".jpg")
            if not cv2.imwrite(str(target), drawn):
                raise InputError(f"{target}: cannot write image")


@detector_app.command("eval")
def evaluate(
    model: Annotated[str, typer.Argument(metavar="MODEL.onnx", help=MODEL_HELP)],
    data: _EvalData,
    split: _Split = "val",
    conf: _Conf = DETECTOR_CONFIDENCE,
    iou: _Iou = 0.5,
    max_images: _MaxImages = 0,
    threads: _Threads = 2,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON document.")] = False,
) -> None:
    """Precision and recall (at --conf) and AP@0.5 per class of an ONNX model on a labelled dataset."""
    from initcli.detector.evaluate import evaluate_model

    if split not in ("val", "train"):
        raise _fail(f"--split: expected val or train, got {split!r}")
    try:
        result = evaluate_model(
            model, data, split=split, conf=conf, iou=iou, max_images=max_images, threads=threads
        )
    except InputError as exc:
        raise _fail(str(exc)) from None
    if json_out:
        typer.echo(json.dumps(result.to_dict(), indent=2))
        return
    console = _console()
    console.print(f"{model} on {data} ({split}, {result.metrics.images} images)")
    console.print(metrics_table(result.metrics, ""))
    console.print(f"mAP@0.5 {result.metrics.map50:.3f}" if result.metrics.map50 is not None else "mAP@0.5 -")
    for w in result.warnings:
        typer.echo(f"bim-init: warning: {w}", err=True)


@detector_app.command()
def calibrate(
    model: Annotated[str, typer.Argument(metavar="MODEL.onnx", help=MODEL_HELP)],
    data: _EvalData,
    out: Annotated[Path, typer.Option("-o", "--out", metavar="PROFILE.json", help="The profile to write.")],
    split: _Split = "val",
    conf: _Conf = DETECTOR_CONFIDENCE,
    iou: Annotated[
        float,
        typer.Option(
            "--iou",
            callback=number_option(PROG, above=0, maximum=1),
            metavar="T",
            help="IoU a detection needs with a labelled box to find it.",
        ),
    ] = 0.5,
    max_images: _MaxImages = 0,
    threads: _Threads = 2,
) -> None:
    """Measure a model's recall by box height, false boxes per image and class confusion on a
    labelled dataset: a profile for the simulated detector (sim.detector.profile)."""
    from initcli.detector.calibrate import calibrate_model
    from initcli.detector.profile import PROFILE_FORMAT, write_profile

    if split not in ("val", "train"):
        raise _fail(f"--split: expected val or train, got {split!r}")
    try:
        profile_out = OutputFile(out, "-o/--out", (".json",), json_of_format(PROFILE_FORMAT), "profile")
        check_outputs([data, None if model == "default" else Path(model)], [profile_out])
        profile, warnings = calibrate_model(model, data, split, conf, iou, max_images, threads)
        write_profile(profile, out)
    except InputError as exc:
        raise _fail(str(exc)) from None
    for w in warnings:
        typer.echo(f"bim-init: warning: {w}", err=True)
    typer.echo(f"wrote {out}: {profile.model} on {profile.images} images of {data} ({split}), conf {conf:g}")
    for cls, table in profile.recall.items():
        found, boxes = sum(table.found), sum(table.boxes)
        bins = ", ".join(
            f"{table.edges[k]:g}-{table.edges[k + 1]:g} px {f}/{b}"
            for k, (f, b) in enumerate(zip(table.found, table.boxes, strict=True))
        )
        typer.echo(f"  recall {cls}: {found}/{boxes} ({bins})")
    fp = ", ".join(f"{c} {v:.3f}" for c, v in profile.false_boxes.items())
    typer.echo(f"  false boxes per image: {profile.false_boxes_per_image():.3f} ({fp})")
    for cls, row in profile.confusion.items():
        typer.echo(f"  found {cls} given as: " + ", ".join(f"{c} {n}" for c, n in row.items()))
