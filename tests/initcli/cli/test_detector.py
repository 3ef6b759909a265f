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
