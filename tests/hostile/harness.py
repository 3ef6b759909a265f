"""The hostile-input corpus: a case is a command line run in its own copy of a workspace of valid
inputs plus the hostile ones its ``setup`` makes; the checks are the issue's promises.

A refusal (exit 2) must print exactly one line, ``bim-init: error: ...`` or ``bim-extract: error:
...``, matching the case's pattern, no traceback, within the case's timeout, and leave the folder
exactly as it was: every file's bytes and inode, nothing created or removed (no output, no staging
folder, no probe). A case that succeeds (a Latin-1 file name, ``--force`` into a folder of someone
else's files) must leave every file that was there unchanged and nothing of the machinery behind.

The commands run through :mod:`tests.hostile.forkserver` (real child processes of the installed
entry points, without paying their import time per case); :func:`run_script` runs one through the
installed console script itself.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import stat
import subprocess
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
MACHINERY = (".bim-stage.", ".bim-old.")  # staging and replacement folders of bimkit.atomic


@dataclass(frozen=True)
class Case:
    """One hostile input: ``argv`` (``bim-init ...`` or ``bim-extract ...``, paths relative to the
    case folder; ``{port}`` is the port of the case's server), run after ``setup(folder)``."""

    name: str
    argv: tuple[str, ...]
    pattern: str  # re.search on the one stderr line (refusals) or on stdout + stderr (others)
    setup: Callable[[Path], None] | None = None
    code: int = 2
    timeout: float = 60.0
    changes: tuple[str, ...] = ()  # files a successful case may change (its outputs)
    server: str | None = None  # "plain-ws" | "silent-tcp" | "closed": a server on 127.0.0.1 for {port}
    check: Callable[[Path], None] | None = None  # more assertions on the folder afterwards
    cwd: str = "."  # where in the case folder the command runs
    slow: bool = False

    @property
    def id(self) -> str:
        return re.sub(r"[^A-Za-z0-9_.=-]+", "-", self.name).strip("-")


@dataclass
class Result:
    code: int | None
    stdout: str
    stderr: str
    seconds: float
    timed_out: bool


@dataclass
class Entry:
    kind: str
    inode: int
    size: int
    digest: str = ""


def snapshot(folder: Path) -> dict[str, Entry]:
    """Every entry under ``folder`` (links not followed): kind, inode, size and SHA-1 of the bytes."""
    found: dict[str, Entry] = {}
    for base, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = Path(base) / name
            info = os.lstat(path)
            rel = str(path.relative_to(folder))
            if stat.S_ISLNK(info.st_mode):
                found[rel] = Entry("link", info.st_ino, 0, os.readlink(path))
            elif stat.S_ISDIR(info.st_mode):
                found[rel] = Entry("dir", info.st_ino, 0)
            elif stat.S_ISREG(info.st_mode):
                digest = hashlib.sha1()
                if info.st_blocks * 512 >= info.st_size:  # not a sparse stand-in for a huge file
                    with open(path, "rb") as handle:
                        for block in iter(lambda h=handle: h.read(1 << 20), b""):
                            digest.update(block)
                found[rel] = Entry("file", info.st_ino, info.st_size, digest.hexdigest())
            else:
                found[rel] = Entry("special", info.st_ino, 0)
    return found


def leftovers(folder: Path) -> list[str]:
    return [
        str(p.relative_to(folder))
        for p in folder.rglob("*")
        if p.name.startswith(MACHINERY) or p.name.endswith(".partial")
    ]


@dataclass
class ForkServer:
    """The client of :mod:`tests.hostile.forkserver`: one request at a time."""

    process: subprocess.Popen = field(init=False)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def __post_init__(self) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "tests.hostile.forkserver"],
            cwd=ROOT,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env={**os.environ, "PYTHONPATH": str(ROOT), "NO_COLOR": "1", "COLUMNS": "200"},
        )
        assert self.process.stdout is not None
        ready = self.process.stdout.readline()
        assert json.loads(ready) == {"ready": True}, ready

    def run(self, argv: list[str], cwd: Path, logs: Path, timeout: float) -> Result:
        out, err = logs / "stdout", logs / "stderr"
        request = {"argv": argv, "cwd": str(cwd), "stdout": str(out), "stderr": str(err), "timeout": timeout}
        with self.lock:
            assert self.process.stdin is not None and self.process.stdout is not None
            self.process.stdin.write(json.dumps(request) + "\n")
            self.process.stdin.flush()
            reply = json.loads(self.process.stdout.readline())
        return Result(
            reply["code"],
            out.read_text(errors="replace"),
            err.read_text(errors="replace"),
            reply["seconds"],
            reply["timed_out"],
        )

    def close(self) -> None:
        if self.process.stdin is not None:
            self.process.stdin.close()
        self.process.wait(timeout=30)


def run_script(argv: list[str], cwd: Path, timeout: float) -> Result:
    """``argv`` through the installed console script (``.venv/bin/bim-init``), as a user runs it."""
    import time

    started = time.monotonic()
    try:
        done = subprocess.run(
            [str(BIN / argv[0]), *argv[1:]],
            cwd=cwd,
            capture_output=True,
            timeout=timeout,
            stdin=subprocess.DEVNULL,
            env={**os.environ, "NO_COLOR": "1", "COLUMNS": "200"},
        )
    except subprocess.TimeoutExpired as exc:
        return Result(None, str(exc.stdout or ""), str(exc.stderr or ""), timeout, True)
    return Result(
        done.returncode,
        done.stdout.decode(errors="replace"),
        done.stderr.decode(errors="replace"),
        time.monotonic() - started,
        False,
    )


def prepare(case: Case, workspace: Path, folder: Path) -> None:
    shutil.copytree(workspace, folder, symlinks=True)
    if case.setup is not None:
        case.setup(folder)


def verify(case: Case, folder: Path, before: dict[str, Entry], result: Result) -> None:
    """The issue's promises for one case (an AssertionError names what was broken)."""
    shown = f"{case.name}: exit {result.code} in {result.seconds:.1f} s\nstdout: {result.stdout[-2000:]}\n"
    shown += f"stderr: {result.stderr[-3000:]}"
    assert not result.timed_out, f"hang (killed after {case.timeout:.0f} s): {shown}"
    both = result.stdout + result.stderr
    assert "Traceback" not in both, f"a traceback: {shown}"
    assert result.code == case.code, f"exit code {result.code}, expected {case.code}: {shown}"
    after = snapshot(folder)
    if case.code == 2:
        lines = [line for line in result.stderr.splitlines() if line.strip()]
        assert len(lines) == 1, f"{len(lines)} lines on stderr, expected one: {shown}"
        assert re.match(r"^bim-(init|extract): error: ", lines[0]), shown
        assert re.search(case.pattern, lines[0]), f"no /{case.pattern}/ in the line: {shown}"
        changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
        assert not changed, f"the folder changed ({changed[:8]}): {shown}"
    else:
        assert re.search(case.pattern, both), f"no /{case.pattern}/ in the output: {shown}"
        lost = sorted(k for k, v in before.items() if k not in case.changes and after.get(k) != v)
        assert not lost, f"files changed or lost ({lost[:8]}): {shown}"
        assert not leftovers(folder), f"left behind {leftovers(folder)}: {shown}"
    if case.check is not None:
        case.check(folder)
