"""The commands' signal handling: Ctrl-C or SIGTERM that lands while a finaliser runs (llvmlite's
``__del__`` during a numba compile) stops the command as anywhere else, with no traceback, also
when the command would have ended right after the finaliser."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bimkit.cli import EXIT_INTERRUPTED, EXIT_TERMINATED

BUSY_S = 3.0  # s the finaliser runs
# A command that, once, spends BUSY_S in a finaliser (and says when it is in there), then idles 5 s
# ("idle") or ends at once ("end"); it prints "finished" if it got to its end.
SCRIPT = f"""
import sys, time
import typer
from bimkit.cli import run_cli

app = typer.Typer()
state = {{"busy": True}}


class Finalised:
    def __del__(self):
        if state.pop("busy", False):
            print("in __del__", flush=True)
            end = time.time() + {BUSY_S}
            while time.time() < end:
                pass


@app.command()
def main(then: str) -> None:
    Finalised()
    if then == "idle":
        time.sleep(5)
    print("finished", flush=True)


run_cli(app, "demo")
"""
SIGNALS = [(signal.SIGTERM, EXIT_TERMINATED, "demo: terminated"), (signal.SIGINT, EXIT_INTERRUPTED, "")]


def _interrupted(tmp_path: Path, sig: int, then: str) -> tuple[int, str, str, float]:
    """Run the command, send ``sig`` while it is in its finaliser: exit code, stdout, stderr, and
    the seconds from the signal to the end."""
    script = tmp_path / "demo.py"
    script.write_text(SCRIPT)
    process = subprocess.Popen(
        [sys.executable, str(script), then], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "in __del__"
    time.sleep(0.5)
    sent = time.monotonic()
    process.send_signal(sig)
    out, err = process.communicate(timeout=60)
    return process.returncode, out, err, time.monotonic() - sent


@pytest.mark.parametrize("then", ["idle", "end"])
@pytest.mark.parametrize(("sig", "code", "word"), SIGNALS, ids=["SIGTERM", "SIGINT"])
def test_a_signal_inside_a_finaliser_stops_the_command_when_it_is_done(
    tmp_path: Path, sig: int, code: int, word: str, then: str
) -> None:
    """``idle``: the command would go on for 5 s, and stops when the finaliser is done; ``end``: it
    ends right after the finaliser, before the signal held off comes, and still exits as signalled."""
    returncode, out, err, took = _interrupted(tmp_path, sig, then)
    assert returncode == code, err
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert word in err  # SIGTERM says so; Ctrl-C, as typer has it, only sets the exit code
    if then == "idle":
        assert "finished" not in out  # the command stopped, it did not go on
        assert BUSY_S - 1.0 < took < BUSY_S + 2.0  # held off until the finaliser ended, no later


def test_a_signal_in_an_llvmlite_callback_is_held_off_like_one_in_a_finaliser() -> None:
    """A numba compile calls back into llvmlite's Python from C (the object cache): an exception
    raised there is ignored and the C code goes on with no result (a segmentation fault, seen once
    in the signal tests), so a signal is held off there as inside a ``__del__``; elsewhere it is not."""
    from bimkit.cli import _in_finaliser

    where = {}
    for name, path in (
        ("callback", f"{Path('site-packages') / 'llvmlite' / 'binding' / 'executionengine.py'}"),
        ("plain", f"{Path('site-packages') / 'initcli' / 'core' / 'raycast.py'}"),
    ):
        exec(compile("def here():\n    return sys._getframe()\n", path, "exec"), {"sys": sys}, where)
        assert _in_finaliser(where["here"]()) is (name == "callback")


STORAGE = """
import errno, sys
import typer
from bimkit.cli import run_cli

app = typer.Typer()


@app.command()
def main(code: str) -> None:
    names = {"EROFS": "/x/out.png", "ENAMETOOLONG": "/x/" + "9" * 5000 + ".yaml"}
    raise OSError(getattr(errno, code), "the reason", *([names[code]] if code in names else []))


run_cli(app, "tool")
"""


@pytest.mark.parametrize("code", ["ENOSPC", "EROFS", "EDQUOT", "ENAMETOOLONG"])
def test_a_full_disk_or_a_read_only_folder_is_one_line_and_exit_2(tmp_path: Path, code: str) -> None:
    script = tmp_path / "tool.py"
    script.write_text(STORAGE)
    done = subprocess.run([sys.executable, str(script), code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    (line,) = done.stderr.splitlines()
    assert line.startswith("tool: error: stopped: the reason")
    assert ("/x/out.png" in line) == (code == "EROFS")
    assert len(line) < 200  # a name of 5000 characters is cut short


def test_an_os_error_of_the_program_itself_stays_a_traceback(tmp_path: Path) -> None:
    """A bad file descriptor is a bug, not the machine's storage: it is not hidden."""
    script = tmp_path / "tool.py"
    script.write_text(STORAGE)
    done = subprocess.run([sys.executable, str(script), "EBADF"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 1 and "Traceback" in done.stderr
