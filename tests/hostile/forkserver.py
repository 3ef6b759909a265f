"""Run the installed CLIs' entry points in fresh child processes, fast: this process imports them once
(numpy, numba, OpenCV, typer, ... take seconds), then forks one child per request.

A child is a real process: its own stdin (``/dev/null``), stdout and stderr (files), working
folder, exit code and signals; it runs the console script's entry point (``initcli.cli.main:main``
for ``bim-init``, ``bimtools.cli:main`` for ``bim-extract``) with ``sys.argv`` set, exactly as the
script does, so an uncaught exception is a traceback on its stderr and exit code 1, as it would be
from the console script. The server kills a child (and its process group) that runs past its
timeout and says so.

Protocol (JSON lines): a request on stdin ``{"argv": [...], "cwd": ..., "stdout": ..., "stderr":
..., "timeout": s, "env": {...}}``; a reply on stdout ``{"code": int | null, "seconds": s,
"timed_out": bool}``. The first line the server writes is ``{"ready": true}``.
"""

from __future__ import annotations

import io
import json
import os
import signal
import sys
import time
import traceback


def _warm() -> dict[str, object]:
    import bimtools.cli
    import bimtools.extract.output  # noqa: F401 - imported by the commands when they run
    import bimtools.extract.pipeline  # noqa: F401
    import initcli.cli.main
    import initcli.cli.plot_hypotheses  # noqa: F401 - matplotlib
    import initcli.config  # noqa: F401
    import initcli.detector.runtime  # noqa: F401 - onnxruntime
    import initcli.eval.campaign  # noqa: F401
    import initcli.ros.bag_reader  # noqa: F401
    import initcli.session.simulated  # noqa: F401

    return {"bim-init": initcli.cli.main.main, "bim-extract": bimtools.cli.main}


def _child(request: dict, entries: dict[str, object]) -> None:
    """In the forked child: become the console script and never return."""
    code = 1
    try:
        os.setpgid(0, 0)
        os.chdir(request["cwd"])
        null = os.open(os.devnull, os.O_RDONLY)
        out = os.open(request["stdout"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        err = os.open(request["stderr"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        for fd, target in ((null, 0), (out, 1), (err, 2)):
            os.dup2(fd, target)
            os.close(fd)
        sys.stdin = io.TextIOWrapper(io.FileIO(0, "r", closefd=False), encoding="utf-8")
        sys.stdout = io.TextIOWrapper(io.FileIO(1, "w", closefd=False), encoding="utf-8")
        sys.stderr = io.TextIOWrapper(
            io.FileIO(2, "w", closefd=False), encoding="utf-8", errors="backslashreplace", line_buffering=True
        )
        os.environ.update(request.get("env") or {})
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        argv = list(
            request["argv"]
        )  # a file name that is not UTF-8 arrives surrogate-escaped, as in sys.argv
        sys.argv = argv
        main = entries[argv[0]]
        try:
            main()  # type: ignore[operator]
            code = 0
        except SystemExit as exc:
            if exc.code is None:
                code = 0
            elif isinstance(exc.code, int):
                code = exc.code
            else:
                print(exc.code, file=sys.stderr)
                code = 1
        except BaseException:  # what the interpreter prints for an uncaught exception
            traceback.print_exc()
            code = 1
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # noqa: BLE001 - the child ends anyway
                pass
        os._exit(code)


def _serve_one(request: dict, entries: dict[str, object]) -> dict:
    started = time.monotonic()
    pid = os.fork()
    if pid == 0:
        _child(request, entries)
    deadline = started + float(request.get("timeout", 60))
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            code = os.waitstatus_to_exitcode(status)
            return {"code": code, "seconds": time.monotonic() - started, "timed_out": False}
        if time.monotonic() > deadline:
            for target in (lambda: os.killpg(pid, signal.SIGKILL), lambda: os.kill(pid, signal.SIGKILL)):
                try:
                    target()
                except OSError:
                    pass
            os.waitpid(pid, 0)
            return {"code": None, "seconds": time.monotonic() - started, "timed_out": True}
        time.sleep(0.01)


def main() -> None:
    entries = _warm()
    protocol = os.fdopen(os.dup(1), "w", buffering=1)
    requests = os.fdopen(os.dup(0), "r")
    print(json.dumps({"ready": True}), file=protocol)
    for line in requests:
        if line.strip():
            print(json.dumps(_serve_one(json.loads(line), entries)), file=protocol)


if __name__ == "__main__":
    main()
