"""The commands' signal handling: Ctrl-C or SIGTERM that lands while a finaliser runs (llvmlite's
``__del__`` during a numba compile) stops the command as anywhere else, with no traceback."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bimkit.cli import EXIT_INTERRUPTED, EXIT_TERMINATED

# A command that, once, spends a long while in a finaliser (and says when it is in there), then
# idles; it would print "finished" if the signal were lost.
SCRIPT = """
import sys, time
import typer
from bimkit.cli import run_cli

app = typer.Typer()
state = {"busy": True}


class Finalised:
    def __del__(self):
        if state.pop("busy", False):
            print("in __del__", flush=True)
            end = time.time() + 20
            while time.time() < end:
                pass


@app.command()
def main() -> None:
    Finalised()
    time.sleep(5)
    print("finished", flush=True)


run_cli(app, "demo")
"""


@pytest.mark.parametrize(
    ("sig", "code", "word"),
    [(signal.SIGTERM, EXIT_TERMINATED, "terminated"), (signal.SIGINT, EXIT_INTERRUPTED, "")],
    ids=["SIGTERM", "SIGINT"],
)
def test_a_signal_inside_a_finaliser_still_stops_the_command(
    tmp_path: Path, sig: int, code: int, word: str
) -> None:
    script = tmp_path / "demo.py"
    script.write_text(SCRIPT)
    process = subprocess.Popen(
        [sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "in __del__"
    time.sleep(0.2)
    started = time.monotonic()
    process.send_signal(sig)
    out, err = process.communicate(timeout=60)
    assert process.returncode == code, err
    assert "finished" not in out  # the command stopped, it did not go on
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert word in err  # SIGTERM says so; Ctrl-C, as typer has it, only sets the exit code
    assert time.monotonic() - started < 25  # no later than the finaliser's end
