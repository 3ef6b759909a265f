"""Training and export (the [train] extra; skipped without torch): a few steps reduce the loss on a
tiny rendered dataset, a checkpoint resumes, and the ONNX export equals PyTorch within 1e-4."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from typer.testing import CliRunner

from bimtools.extract.output import write_site  # noqa: E402
from bimtools.extract.pipeline import extract_site  # noqa: E402
from initcli.cli.detector import detector_app  # noqa: E402
from initcli.detector.runtime import Detector  # noqa: E402
from initcli.detector.synth.dataset import SynthOptions, write_dataset  # noqa: E402
from initcli.detector.training.checkpoint import load_checkpoint  # noqa: E402
from initcli.detector.training.export import export_onnx  # noqa: E402
from initcli.detector.training.train import TrainOptions, build_targets, train  # noqa: E402
from tests.helpers import SAMPLES, SCHEMAS

torch = pytest.importorskip("torch")


onnx = pytest.importorskip("onnx")


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("detector_train")
    site = root / "block_a"
    write_site(site, extract_site(SAMPLES / "block_a.ifc"), preview=False)
    out = root / "ds"
    write_dataset(
        [site], out, SynthOptions(images=32, width=160, height=120, seed=5, val_fraction=0.25, workers=1)
    )
    return out / "data.yaml"


def test_targets_peak_at_box_centre():
    hm, box_t, box_w = build_targets(np.array([[16.0, 8.0, 48.0, 72.0]]), np.array([1]), 64, 3)
    assert hm.shape == (3, 8, 8) and hm[1].max() == 1.0
    assert np.unravel_index(hm[1].argmax(), (8, 8)) == (5, 4)  # centre (32, 40) px -> cell (row 5, col 4)
    assert hm[0].max() == 0.0 and hm[2].max() == 0.0
    assert (box_w > 0).sum() >= 1 and np.allclose(box_t[:, 5, 4], [16, 8, 48, 72])


def test_training_reduces_loss_and_exports(tiny_dataset, tmp_path):
    torch.manual_seed(0)
    losses: list[float] = []

    def on_event(kind: str, info: dict) -> None:
        if kind == "step":
            losses.append(info["last"])

    out = tmp_path / "model.pt"
    opts = TrainOptions(
        data=tiny_dataset,
        epochs=10,
        imgsz=128,
        batch=8,
        lr=3e-3,
        out=out,
        val_max=8,
        widths=(8, 16, 24, 32, 48),
        neck=24,
        backbone="residual",
        balance=False,  # the plain training machinery: no resampling, no camera degradations
        camera_aug=0.0,
    )
    ckpt = train(opts, on_event)
    assert len(losses) == 30  # 24 train images, batch 8, 10 epochs
    assert np.mean(losses[-4:]) < 0.8 * np.mean(losses[:4]), losses
    assert ckpt["epoch"] == 10 and ckpt["names"] == ["door", "lift", "stairs"]
    assert out.with_suffix(".csv").exists()
    history = load_checkpoint(out)["history"]
    assert len(history) == 10 and set(history[-1]["metrics"]["classes"]) == {"door", "lift", "stairs"}

    # --resume continues from the checkpoint's epoch
    more = train(TrainOptions(**{**opts.__dict__, "epochs": 11, "resume": True}), None)
    assert more["epoch"] == 11 and len(more["history"]) == 11
    # --init starts a new run (epoch 1) from the trained weights
    tuned = tmp_path / "tuned.pt"
    fine = train(
        TrainOptions(**{**opts.__dict__, "epochs": 1, "out": tuned, "init": str(out), "max_steps": 1}), None
    )
    assert fine["epoch"] == 1 and fine["arch"] == ckpt["arch"]

    onnx_path = tmp_path / "model.onnx"
    report = export_onnx(out, onnx_path)
    assert report.max_abs_diff <= 1e-4
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("model.onnx")) == ["model.onnx"]
    model = onnx.load(str(onnx_path))
    meta = {p.key: p.value for p in model.metadata_props}
    assert meta["names"] == "{0: 'door', 1: 'lift', 2: 'stairs'}" and meta["imgsz"] == "[128, 128]"
    assert "bim_init.preprocess" in meta
    dims = [d.dim_value for d in model.graph.input[0].type.tensor_type.shape.dim]
    assert dims == [1, 3, 128, 128]
    det = Detector(onnx_path, conf=0.01)
    assert det.layout == "yolov8" and det.names == ["door", "lift", "stairs"]
    assert isinstance(det.detect(np.zeros((120, 160, 3), np.uint8)), list)

    result = CliRunner().invoke(detector_app, ["eval", str(onnx_path), "--data", str(tiny_dataset), "--json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    jsonschema.validate(doc, json.loads((SCHEMAS / "detector_eval.schema.json").read_text()))
    assert set(doc["classes"]) == {"door", "lift", "stairs"} and doc["images"] == 8
