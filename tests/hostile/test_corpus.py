"""The hostile-input corpus (issue 29): every case of the tables in ``tests/hostile/cases_*.py``, run
as a child process of the installed entry point in its own copy of the workspace, with a timeout;
refused with exit code 2 and one line, nothing lost, changed or left behind, no hang, no traceback.

A few cases also run through the installed console scripts themselves (``test_console_script``).
"""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from tests.hostile.cases_misc import ROSBRIDGE, TRACEBACKS, WORK
from tests.hostile.cases_outputs import SACRED, UNWRITABLE
from tests.hostile.cases_parsing import (
    BAGS,
    CONFIGS,
    DATASETS,
    DEVICES,
    LOGS,
    MAPS,
    MODELS,
    SUMMARIES,
    YAML,
)
from tests.hostile.harness import Case, ForkServer, prepare, run_script, snapshot, verify
from tests.hostile.workspace import build
from tests.initcli.ros.rosbridge_server import PlainWebsocketServer

CASES: list[Case] = [
    *SACRED,
    *UNWRITABLE,
    *YAML,
    *CONFIGS,
    *MAPS,
    *MODELS,
    *DATASETS,
    *LOGS,
    *DEVICES,
    *BAGS,
    *SUMMARIES,
    *WORK,
    *TRACEBACKS,
    *ROSBRIDGE,
]
CONSOLE = [  # through .venv/bin/bim-init and bim-extract themselves
    "bag2log -o the bag itself",
    "extract DIR/model.ifc -o DIR --force",
    "billion laughs in a site config",
    "log is /dev/zero",
    "eval --executor ray --address 127.0.0.1:1",
]


def test_the_corpus_is_large_and_its_names_unique() -> None:
    assert len(CASES) >= 100
    assert len({c.id for c in CASES}) == len(CASES)
    assert set(CONSOLE) <= {c.name for c in CASES}


@pytest.fixture(scope="module")
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return build(tmp_path_factory.mktemp("hostile") / "workspace")


@pytest.fixture(scope="module")
def forkserver() -> Iterator[ForkServer]:
    server = ForkServer()
    yield server
    server.close()


@contextmanager
def _silent_tcp() -> Iterator[int]:
    """A TCP server on 127.0.0.1 that accepts connections and never says a word."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(8)
    listener.settimeout(0.2)
    held: list[socket.socket] = []
    stop = threading.Event()

    def accept() -> None:
        while not stop.is_set():
            try:
                held.append(listener.accept()[0])
            except OSError:
                continue

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        yield listener.getsockname()[1]
    finally:
        stop.set()
        thread.join(timeout=2)
        for conn in held:
            conn.close()
        listener.close()


@contextmanager
def _server(kind: str | None) -> Iterator[int | None]:
    if kind is None:
        yield None
    elif kind == "silent-tcp":
        with _silent_tcp() as port:
            yield port
    else:
        with PlainWebsocketServer(echo=kind == "echo-ws") as server:
            yield server.port


def _run(case: Case, workspace: Path, tmp_path: Path, runner) -> None:
    folder = tmp_path / "case"
    prepare(case, workspace, folder)
    logs = tmp_path / "logs"
    logs.mkdir()
    before = snapshot(folder)
    with _server(case.server) as port:
        argv = [a.replace("{port}", str(port)) for a in case.argv]
        result = runner(argv, folder / case.cwd, logs, case.timeout)
    verify(case, folder, before, result)


@pytest.mark.parametrize(
    "case", [pytest.param(c, id=c.id, marks=[pytest.mark.slow] if c.slow else []) for c in CASES]
)
def test_hostile_input(case: Case, workspace: Path, forkserver: ForkServer, tmp_path: Path) -> None:
    _run(case, workspace, tmp_path, forkserver.run)


@pytest.mark.parametrize("name", CONSOLE)
def test_console_script(name: str, workspace: Path, tmp_path: Path) -> None:
    case = next(c for c in CASES if c.name == name)
    _run(case, workspace, tmp_path, lambda argv, cwd, logs, timeout: run_script(argv, cwd, timeout))
