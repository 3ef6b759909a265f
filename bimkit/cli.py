"""Command-line plumbing shared by ``bim-extract`` and ``bim-init``: option range callbacks, the one
error line, and the console-script runner that turns usage errors into that line and exit code 2."""

from __future__ import annotations

import errno
import inspect
import os
import re
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup

from bimkit.checks import range_problem
from bimkit.errors import EXIT_BAD_INPUT

__all__ = [
    "EXIT_INTERRUPTED",
    "EXIT_TERMINATED",
    "HELP",
    "HelpGroup",
    "STORAGE_ERRORS",
    "Terminated",
    "error_line",
    "fail",
    "native_stderr_silenced",
    "number_option",
    "run_cli",
    "storage_problem",
    "summary",
]

EXIT_INTERRUPTED = 130  # Ctrl-C (128 + SIGINT)
EXIT_TERMINATED = 143  # SIGTERM (128 + SIGTERM)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is, like Ctrl-C: every ``finally`` and ``with`` runs (staged
    outputs removed, partial results kept as after an interrupt)."""


_terminated: list[int] = []  # the SIGTERMs received (typer turns the interrupt into exit code 130)
DEFER_S = 0.05  # s between two deliveries of a signal held off inside a finaliser ...
DEFER_MAX_S = 5.0  # ... for at most this long: then it is raised there all the same
_deferred: dict[int, float] = {}  # signal -> when it was first held off inside a finaliser
_resend: set[int] = set()  # signals whose delivery again is scheduled


def _in_finaliser(frame: FrameType | None) -> bool:
    """Is ``frame``, or a frame that called it, an object's ``__del__`` or llvmlite's (a numba
    compile calls back into Python from C there: an exception raised in such a ctypes callback is
    printed as "Exception ignored" and the C code goes on with no result, a segmentation fault)?"""
    while frame is not None:
        code = frame.f_code
        if code.co_name == "__del__" or f"{os.sep}llvmlite{os.sep}" in code.co_filename:
            return True
        frame = frame.f_back
    return False


def _send_again(signum: int) -> None:
    _resend.discard(signum)
    if signum in _deferred:  # not raised in the meantime (by a signal from outside)
        # to the main thread: sent to the process, it may land on this one, and a main thread
        # asleep in a system call would not wake to run the handler
        signal.pthread_kill(threading.main_thread().ident or 0, signum)


def _on_signal(signum: int, frame: FrameType | None) -> None:
    """SIGTERM raises :class:`Terminated`, SIGINT ``KeyboardInterrupt``, where the program is. Not
    inside a finaliser (llvmlite's ``__del__``, in the middle of a numba compile) or an llvmlite
    callback: an exception raised there is swallowed, printed as "Exception ignored" with a
    traceback, and the command goes on (or, from a callback, crashes). There the signal is held off
    and sent again every ``DEFER_S`` until the finaliser is done (one such delivery at a time; a
    finaliser still running after ``DEFER_MAX_S`` gets it raised)."""
    frame = frame if frame is not None else sys._getframe(1)  # called by hand (bimkit.atomic)
    now = time.monotonic()
    if _in_finaliser(frame) and now - _deferred.setdefault(signum, now) < DEFER_MAX_S:
        if signum not in _resend:
            _resend.add(signum)
            timer = threading.Timer(DEFER_S, _send_again, (signum,))
            timer.daemon = True  # a command that ends meanwhile ends (run_cli reads _deferred)
            timer.start()
        return
    _deferred.pop(signum, None)
    if signum != signal.SIGTERM:
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a second SIGTERM ends the process at once
    _terminated.append(signum)
    raise Terminated()


def summary(command: Any) -> str:
    """A command's line in its group's help: its ``short_help``, or the first sentence of its help,
    whole (click cuts it at the column's width with "...")."""
    if getattr(command, "short_help", None):
        return " ".join(str(command.short_help).split())
    paragraph = inspect.cleandoc(getattr(command, "help", None) or "").split("\n\n")[0]
    text = " ".join(paragraph.replace("\b", " ").split())
    return re.split(r"(?<=[.!?])\s+(?=[A-Z`])", text, maxsplit=1)[0]


class HelpGroup(TyperGroup):
    """A command group whose help lists each command with its whole first sentence, wrapped."""

    def format_commands(self, ctx: Any, formatter: Any) -> None:
        rows = []
        for name in self.list_commands(ctx):
            command = self.get_command(ctx, name)
            if command is not None and not command.hidden:
                rows.append((name, summary(command)))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


# The help of every command: click's plain layout, wrapped to the terminal (at most 80 columns).
# Rich's help panels squeeze the option column of a wide table until long names and metavars are
# cut with "…" (``--detections-to…``), and read "[default: ...]" in a help text as a markup tag
# and drop it ("Output folder ."); bim-extract and bim-init share this layout.
HELP: dict[str, Any] = {"rich_markup_mode": None, "cls": HelpGroup}


# What the machine's storage, not the command, refuses: a full disk or quota, a read-only or
# vanished folder, a file too large, a failing device. One line and exit 2, as for bad input.
STORAGE_ERRORS = frozenset(
    {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM, errno.ENOENT, errno.ENOTDIR}
    | {errno.EFBIG, errno.EIO, errno.ESTALE, errno.ENAMETOOLONG, errno.ELOOP}
)
SHOWN_NAME = 120  # characters of a file name an error line shows at most


def storage_problem(exc: OSError) -> str:
    """What a storage error says to a user: the reason, and the file where the error names one
    (a failed write does not)."""
    name = str(exc.filename) if exc.filename else ""
    if len(name) > SHOWN_NAME:
        name = name[: SHOWN_NAME - 3] + "..."
    where = f" ({name})" if name else ""
    return f"stopped: {exc.strerror or exc}{where}"


def error_line(prog: str, message: object) -> str:
    """``prog: error: message`` on one line (white space folded)."""
    return f"{prog}: error: {' '.join(str(message).split())}"


def number_option(
    prog: str,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    above: float | None = None,
    below: float | None = None,
) -> Callable[..., Any]:
    """A typer/click option callback: a number outside the range (or not finite) is one line on
    stderr (``prog: error: --resolution: nan is not a finite number``) and exit code 2."""

    def callback(ctx: Any, param: Any, value: Any) -> Any:
        if value is None or getattr(ctx, "resilient_parsing", False):
            return value
        values = value if isinstance(value, list | tuple) else [value]
        for v in values:
            problem = range_problem(v, minimum=minimum, maximum=maximum, above=above, below=below)
            if problem is not None:
                name = max(getattr(param, "opts", None) or [str(param.name)], key=len)
                fail(prog, f"{name}: {problem}")
        return value

    return callback


@contextmanager
def native_stderr_silenced() -> Iterator[int]:
    """Native libraries (libpng, OpenCV's logger, Ray's core) print to file descriptor 2 past
    Python; around a call into one that is fed a bad input, their lines go to /dev/null so that
    the error stays the one line the command prints. Yields a descriptor of the real stderr."""
    sys.stderr.flush()
    saved = os.dup(2)
    quiet = os.open(os.devnull, os.O_WRONLY)
    os.dup2(quiet, 2)
    os.close(quiet)
    try:
        yield saved
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def fail(prog: str, message: object) -> NoReturn:
    """Print ``prog: error: message`` as one line on stderr and exit with code 2."""
    typer.echo(error_line(prog, message), err=True)
    raise typer.Exit(EXIT_BAD_INPUT)


def run_cli(app: Any, prog: str) -> None:
    """Run a typer ``app`` as a console script: a usage error (an unknown option, ``--seed abc``) is
    one line on stderr and exit 2 like every other bad input, not click's usage block; Ctrl-C is 130,
    SIGTERM takes the same path (:class:`Terminated`) and is 143."""
    try:  # typer >= 0.20 carries its own copy of click
        from typer._click import exceptions as cx
    except ImportError:  # pragma: no cover - older typer on click
        from click import exceptions as cx  # type: ignore[no-redef]

    signal.signal(signal.SIGTERM, _on_signal)
    signal.signal(signal.SIGINT, _on_signal)
    reconfigure = getattr(sys.stdout, "reconfigure", None)
    if reconfigure is not None:  # a file name that is not UTF-8 is printed as its bytes, not a crash
        reconfigure(errors="surrogateescape")
    try:
        code = app(standalone_mode=False)
    except getattr(cx, "NoArgsIsHelpError", ()) as exc:  # a bare command: its help, as before
        if exc.ctx is not None:
            print(exc.ctx.get_help(), file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)
    except cx.UsageError as exc:
        where = f" ({exc.ctx.command_path})" if exc.ctx is not None else ""
        print(f"{prog}: error{where}: {' '.join(exc.format_message().split())}", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)
    except cx.ClickException as exc:
        print(error_line(prog, exc.format_message()), file=sys.stderr)
        sys.exit(exc.exit_code)
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        sys.exit(EXIT_INTERRUPTED)
    except OSError as exc:
        if exc.errno not in STORAGE_ERRORS:
            raise
        print(error_line(prog, storage_problem(exc)), file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)
    if signal.SIGINT in _deferred:  # held off in a finaliser, and the command ended before it came
        sys.exit(EXIT_INTERRUPTED)
    if _terminated or signal.SIGTERM in _deferred:
        print(f"{prog}: terminated", file=sys.stderr)
        sys.exit(EXIT_TERMINATED)
    sys.exit(code if isinstance(code, int) else 0)
