"""``bim-init detector``: synth with a preview sheet, and a corrupt model as one line of error."""

from __future__ import annotations

import subprocess
import sys

import numpy as np


def test_synth_cli_with_preview(site_a, tmp_path):
    from typer.testing import CliRunner

    from initcli.cli.detector import detector_app

    out, sheet = tmp_path / "ds", tmp_path / "sheet.png"
    args = ["synth", "--site", str(site_a), "--out", str(out), "--images", "6", "--size", "160x120"]
    result = CliRunner().invoke(detector_app, [*args, "--workers", "1", "--preview", str(sheet)])
    assert result.exit_code == 0, result.output
    assert sheet.stat().st_size > 1000 and (out / "data.yaml").exists()
    bad = CliRunner().invoke(detector_app, ["synth", "--site", str(tmp_path / "nope"), "--out", str(out)])
    assert bad.exit_code == 2 and "no such file or folder" in bad.output
    bad_size = CliRunner().invoke(detector_app, [*args, "--size", "big"])
    assert bad_size.exit_code == 2 and "--size" in bad_size.output


def test_cli_corrupt_model_one_line(tmp_path):
    corrupt = tmp_path / "model.onnx"
    corrupt.write_text("definitely not onnx")
    image = tmp_path / "a.png"
    import cv2

    cv2.imwrite(str(image), np.zeros((32, 32, 3), np.uint8))
    script = "from initcli.cli.main import main; main()"
    result = subprocess.run(
        [sys.executable, "-c", script, "detector", "predict", str(corrupt), str(image)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "model.onnx" in lines[0] and "Traceback" not in result.stderr


def test_calibrate_cli_writes_a_profile_and_refuses_bad_input_in_one_line(tmp_path):
    import json

    from typer.testing import CliRunner

    from initcli.cli.detector import detector_app
    from initcli.detector.profile import read_profile
    from tests.initcli.detector.test_calibrate import _dataset

    data = _dataset(tmp_path / "ds", n=3)
    out = tmp_path / "p.json"
    ok = CliRunner().invoke(detector_app, ["calibrate", "default", "--data", str(data), "-o", str(out)])
    assert ok.exit_code == 0, ok.output
    assert read_profile(out).images == 3 and "recall door" in ok.output
    assert json.loads(out.read_text())["dataset"]["boxes"] == {"door": 3, "lift": 1}
    for args, message in [
        (["--data", str(tmp_path / "none.yaml"), "-o", str(tmp_path / "q.json")], "none.yaml: no such file"),
        (["--data", str(data), "-o", str(tmp_path / "q.txt")], "-o/--out"),
        (
            ["--data", str(data), "-o", str(tmp_path / "q.json"), "--split", "test"],
            "--split: expected val or train",
        ),
        (["--data", str(data), "-o", str(tmp_path / "q.json"), "--iou", "0"], "--iou"),
        (["--data", str(data), "-o", str(data)], "data.yaml"),
    ]:
        bad = CliRunner().invoke(detector_app, ["calibrate", "default", *args])
        lines = bad.output.strip().splitlines()
        assert bad.exit_code == 2 and len(lines) == 1 and message in lines[0], bad.output
        assert not (tmp_path / "q.json").exists()


def test_train_refuses_a_dataset_without_a_usable_box_naming_what_was_dropped(tmp_path):
    import cv2
    import pytest
    from typer.testing import CliRunner

    from initcli.cli.detector import detector_app

    pytest.importorskip("torch")
    root = tmp_path / "ds"
    (root / "images" / "train").mkdir(parents=True)
    (root / "labels" / "train").mkdir(parents=True)
    for name in ("a", "b"):
        cv2.imwrite(str(root / "images" / "train" / f"{name}.png"), np.full((48, 64, 3), 90, np.uint8))
    (root / "labels" / "train" / "a.txt").write_text("0 1.5 0.5 0.2 0.2\n0 0.5 1.3 0.2 0.2\n")
    (root / "labels" / "train" / "b.txt").write_text("1 0.5 0.5 0.0 0.2\n")
    (root / "data.yaml").write_text("path: .\ntrain: images/train\nnames: [door, lift, stairs]\n")
    out = tmp_path / "model.pt"
    result = CliRunner().invoke(detector_app, ["train", "--data", str(root / "data.yaml"), "--out", str(out)])
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.exit_code == 2, result.output
    assert len(lines) == 1 and "Traceback" not in result.output, result.stderr
    assert (
        "the train split's 2 image(s) hold 0 usable boxes (3 label(s) were dropped: 2 outside the image"
        in lines[0]
    )
    assert "1 of width or height 0" in lines[0]
    assert not out.exists() and not out.with_suffix(".csv").exists()


def test_export_of_a_checkpoint_missing_a_weight_is_one_line_and_writes_nothing(tmp_path):
    import pytest
    from typer.testing import CliRunner

    from initcli.cli.detector import detector_app

    pytest.importorskip("torch")
    from initcli.detector.training.checkpoint import load_init, save_checkpoint

    ckpt = load_init("default")
    first = next(iter(ckpt["model"]))
    for name, change in (
        ("missing", lambda m: m.pop(first)),
        ("reshaped", lambda m: m.update({first: m[first][:1]})),
    ):
        model = dict(ckpt["model"])
        change(model)
        save_checkpoint(tmp_path / f"{name}.pt", {**ckpt, "model": model})
        out = tmp_path / f"{name}.onnx"
        result = CliRunner().invoke(detector_app, ["export", str(tmp_path / f"{name}.pt"), "-o", str(out)])
        lines = [line for line in result.stderr.splitlines() if line.strip()]
        assert result.exit_code == 2, result.output
        assert len(lines) == 1 and "Traceback" not in result.output, result.stderr
        assert f"{name}.pt: weights" in lines[0] and first in lines[0]
        assert not out.exists()


def test_export_of_a_checkpoint_without_class_names_is_one_line(tmp_path):
    import pytest
    from typer.testing import CliRunner

    from initcli.cli.detector import detector_app

    pytest.importorskip("torch")
    from initcli.detector.training.checkpoint import load_init, save_checkpoint

    ckpt = load_init("default")
    for name, names, said in (
        ("none", None, "no class names"),
        ("empty", [], "0 class names for a network of 3 classes"),
        ("two", ["door", "lift"], "2 class names for a network of 3 classes"),
    ):
        save_checkpoint(tmp_path / f"{name}.pt", {**ckpt, "names": names})
        out = tmp_path / f"{name}.onnx"
        result = CliRunner().invoke(detector_app, ["export", str(tmp_path / f"{name}.pt"), "-o", str(out)])
        assert result.exit_code == 2 and said in result.stderr, result.output
        assert not out.exists()
