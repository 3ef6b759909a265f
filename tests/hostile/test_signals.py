"""SIGTERM and SIGINT (Ctrl-C) sent to a real ``bim-init`` / ``bim-extract`` process while it works:
it ends within seconds, with its exit code (143, 130), one line, and leaves nothing behind -- no
staging folder, no half output, an earlier output folder as it was."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import time
from pathlib import Path

import pytest
import yaml

from tests.helpers import SAMPLES, wait_until
from tests.hostile.harness import BIN, leftovers, snapshot

SIGNALS = [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "")]


def _start(argv: list[str], cwd: Path) -> subprocess.Popen:
    return subprocess.Popen(
        [str(BIN / argv[0]), *argv[1:]],
        cwd=cwd,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env={**os.environ, "NO_COLOR": "1"},
    )


def _interrupt(process: subprocess.Popen, sig: int, grace: float = 20.0) -> tuple[int, str, float]:
    sent = time.monotonic()
    process.send_signal(sig)
    try:
        _, err = process.communicate(timeout=grace)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        pytest.fail(f"still running {grace:.0f} s after signal {sig}")
    return process.returncode, err.decode(errors="replace"), time.monotonic() - sent


def _staging(folder: Path) -> bool:
    """A session is on its way: its log is being written in a staging folder under ``folder``."""
    return any(p.parent.name.startswith(".bim-stage.") for p in folder.rglob("session.jsonl"))


@pytest.fixture()
def run_config(tmp_path: Path) -> Path:
    shutil.copy(SAMPLES / "ntu_hallway.ifc", tmp_path / "model.ifc")
    (tmp_path / "site.yaml").write_text(yaml.safe_dump({"site": {"path": "model.ifc"}}))
    return tmp_path


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS, ids=["SIGTERM", "SIGINT"])
def test_a_signal_during_run_leaves_no_staging_folder(
    run_config: Path, sig: int, code: int, word: str
) -> None:
    before = snapshot(run_config)
    process = _start(["bim-init", "run", "--config", "site.yaml", "--out", "r", "--quiet"], run_config)
    assert wait_until(lambda: _staging(run_config), 60), "the run never staged its output"
    returncode, err, took = _interrupt(process, sig)
    assert returncode == code, (returncode, err)
    assert "Traceback" not in err and took < 15
    assert word in err
    assert not (run_config / "r").exists()
    assert not leftovers(run_config)
    assert snapshot(run_config) == before


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS, ids=["SIGTERM", "SIGINT"])
def test_a_signal_during_a_rerun_keeps_the_earlier_run(
    run_config: Path, sig: int, code: int, word: str
) -> None:
    done = subprocess.run(
        [str(BIN / "bim-init"), "run", "--config", "site.yaml", "--out", "r", "--quiet"],
        cwd=run_config,
        capture_output=True,
        timeout=300,
    )
    assert done.returncode in (0, 1), done.stderr
    (run_config / "r" / "notes.txt").write_text("the user's")
    before = snapshot(run_config)
    process = _start(["bim-init", "run", "--config", "site.yaml", "--out", "r", "--quiet"], run_config)
    assert wait_until(lambda: _staging(run_config / "r"), 60), "the rerun never staged its output"
    returncode, err, _ = _interrupt(process, sig)
    assert returncode == code, (returncode, err)
    assert "Traceback" not in err
    assert not leftovers(run_config)
    assert snapshot(run_config) == before


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS, ids=["SIGTERM", "SIGINT"])
def test_a_signal_during_synth_leaves_no_dataset(
    site_a: Path, tmp_path: Path, sig: int, code: int, word: str
) -> None:
    argv = ["bim-init", "detector", "synth", "--site", str(site_a), "--out", "ds", "--images", "400"]
    process = _start([*argv, "--workers", "1", "--no-depth"], tmp_path)
    assert wait_until(lambda: any(tmp_path.rglob("*.jpg")), 90), "synth never wrote an image"
    returncode, err, took = _interrupt(process, sig)
    assert returncode == code, (returncode, err)
    assert "Traceback" not in err and took < 15
    assert sorted(os.listdir(tmp_path)) == []


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS, ids=["SIGTERM", "SIGINT"])
def test_a_signal_during_eval_keeps_the_trials_and_ends_the_workers(
    run_config: Path, sig: int, code: int, word: str
) -> None:
    (run_config / "eval.yaml").write_text(yaml.safe_dump({"sites": [{"config": "site.yaml"}], "starts": 50}))
    argv = ["bim-init", "eval", "--config", "eval.yaml", "--out", "ev", "--workers", "2", "--methods", "bim"]
    process = _start(argv, run_config)
    results = run_config / "ev" / "results.jsonl"
    assert wait_until(lambda: results.is_file() and results.stat().st_size > 0, 240), "no trial finished"
    returncode, err, took = _interrupt(process, sig)
    assert returncode == code, (returncode, err)
    assert "Traceback" not in err and took < 15, err
    assert "rerun with --resume" in err
    assert not leftovers(run_config)
    assert results.read_text().strip()


@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS, ids=["SIGTERM", "SIGINT"])
def test_a_signal_while_ray_connects_ends_it_at_once(
    site_a: Path, tmp_path: Path, sig: int, code: int, word: str
) -> None:
    """``ray.init`` blocks in native code, where Python's handlers cannot run: the connect watcher
    ends the process on the signal (the issue: 29 s to die after SIGTERM)."""
    pytest.importorskip("ray")
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(8)  # accepts (in the kernel's backlog) and never answers
    port = listener.getsockname()[1]
    try:
        argv = ["bim-init", "survey", str(site_a), "--out", "sv", "--executor", "ray", "--address"]
        process = _start([*argv, f"127.0.0.1:{port}"], tmp_path)
        time.sleep(12)  # imports, the site, the TCP probe (it connects), then ray.init waits
        assert process.poll() is None, process.communicate()
        returncode, err, took = _interrupt(process, sig, grace=10)
    finally:
        listener.close()
    assert returncode == code, (returncode, err)
    assert took < 5, took
    lines = err.strip().splitlines()
    assert len(lines) <= 1 and set(lines) <= {"bim-init: terminated", "bim-init: interrupted"}, err
    assert sorted(os.listdir(tmp_path)) == []
