"""Inputs are sacred: every output path checked against the command's inputs and the file system
before any work starts.

Every command calls :func:`check_outputs` with the paths it reads and the paths it will write. An
output is refused (one :class:`~bimkit.errors.InputError` line, exit code 2) when it

- is one of the inputs (the same path after symbolic links, or the same file under another name:
  a hard link), holds an input (a folder whose replacement would take the input with it) or lies
  inside an input folder (a command never writes into what it reads);
- is the wrong kind: a folder where a file is written, a file where a folder is, a device or a pipe;
- cannot be written: a path through a dangling symbolic link or a file, a folder without write
  permission, a pseudo file system such as ``/proc`` (a probe entry is made and removed);
- is a folder holding files of someone else: refused without ``--force``; with ``--force`` those
  files are kept (:mod:`bimkit.atomic` replaces only what the tool wrote), and a file the tool
  would write over (``writes``) is refused.
"""

from __future__ import annotations

import fnmatch
import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path

from bimkit.atomic import RECORD, STAGE_PREFIX, owned_files
from bimkit.errors import InputError

__all__ = ["OutputFile", "OutputFolder", "check_outputs", "removed_on_storage_error"]


@dataclass(frozen=True)
class OutputFile:
    """A file a command writes (``option`` names it in messages: ``-o/--out``)."""

    path: Path
    option: str
    suffixes: tuple[str, ...] = ()  # the accepted suffixes (lower case, with the dot); () any
    # an existing file is written over only when this says the tool wrote it (None: any file) ...
    owned: Callable[[Path], bool] | None = None
    kind: str = "file"  # ... a file of this kind (for the message)


@dataclass(frozen=True)
class OutputFolder:
    """A folder a command writes: ``markers`` are files it writes there (a folder holding one is an
    earlier run's), ``writes`` the name patterns (fnmatch) of what it writes at the top level."""

    path: Path
    option: str
    markers: tuple[str, ...] = ()
    writes: tuple[str, ...] = ()


def _absolute(path: Path) -> Path:
    return Path(os.path.abspath(os.fspath(path)))


def _identity(path: Path) -> tuple[int, int] | None:
    try:
        info = os.stat(path)
    except OSError:
        return None
    return info.st_dev, info.st_ino


class _Input:
    """An input path, resolved once: its real path, its (device, inode) and whether it is a folder."""

    def __init__(self, path: Path) -> None:
        self.shown = Path(path)
        self.real = Path(os.path.realpath(path))
        self.id = _identity(path)
        self.is_dir = os.path.isdir(path)

    def ancestry(self) -> set[tuple[int, int]]:
        """The identities of every folder above the input (to find an output folder holding it)."""
        ids = set()
        for parent in self.real.parents:
            ident = _identity(parent)
            if ident is not None:
                ids.add(ident)
        return ids


def _refuse(option: str, path: Path, problem: str) -> InputError:
    return InputError(f"{option} {path}: {problem}")


def _check_path(option: str, path: Path) -> Path:
    """The nearest existing folder at or above ``path``'s parent; a dangling link or a file on the
    way is refused."""
    absolute = _absolute(path)
    for above in [absolute, *absolute.parents]:
        if os.path.islink(above) and not os.path.exists(above):
            what = "is" if above == absolute else f"goes through {above}, which is"
            raise _refuse(option, path, f"{what} a symbolic link to a missing target")
    for above in absolute.parents:
        if os.path.exists(above):
            if not os.path.isdir(above):
                raise _refuse(option, path, f"{above} is a file, not a folder")
            return above
    return Path(absolute.anchor)


def _probe(option: str, path: Path, folder: Path) -> None:
    """Make and remove an entry in ``folder``: the only sure test that it can be written."""
    try:
        probe = tempfile.mkdtemp(prefix=f"{STAGE_PREFIX}probe.", dir=folder)
        os.rmdir(probe)
    except OSError as exc:
        raise _refuse(option, path, f"cannot write in {folder} ({exc.strerror or exc})") from None


def _against_inputs(option: str, path: Path, inputs: list[_Input], folder: bool) -> None:
    real = Path(os.path.realpath(path))
    ident = _identity(path)
    above = {i for i in (_identity(p) for p in real.parents) if i is not None}
    for item in inputs:
        if real == item.real or (ident is not None and ident == item.id):
            raise _refuse(
                option, path, f"is the input {item.shown}; choose another name (inputs are never written)"
            )
        if item.is_dir and (item.real in real.parents or (item.id is not None and item.id in above)):
            raise _refuse(option, path, f"is inside the input folder {item.shown}; choose a place outside it")
        if folder and (real in item.real.parents or (ident is not None and ident in item.ancestry())):
            raise _refuse(
                option,
                path,
                f"holds the input {item.shown}; choose another folder (inputs are never replaced)",
            )


def _check_file(out: OutputFile, inputs: list[_Input]) -> None:
    path = out.path
    parent = _check_path(out.option, path)
    if os.path.lexists(path):
        mode = os.stat(path).st_mode
        if stat.S_ISDIR(mode):
            raise _refuse(out.option, path, "is a folder, expected a file name")
        if not stat.S_ISREG(mode):
            raise _refuse(out.option, path, "is a device, pipe or socket, expected a file name")
    _against_inputs(out.option, path, inputs, folder=False)
    if out.owned is not None and os.path.isfile(path) and not out.owned(Path(path)):
        raise _refuse(
            out.option,
            path,
            f"exists and is not a {out.kind} this tool wrote; nothing it did not write is written over:"
            " choose another name",
        )
    if out.suffixes and Path(path).suffix.lower() not in out.suffixes:
        raise _refuse(out.option, path, f"expected a file name ending in {' or '.join(out.suffixes)}")
    _probe(out.option, path, parent if not os.path.exists(path) else _absolute(path).parent)


def _check_folder(out: OutputFolder, inputs: list[_Input], force: bool) -> None:
    path = out.path
    nearest = _check_path(out.option, path)
    if os.path.lexists(path) and not os.path.isdir(path):
        raise _refuse(out.option, path, "is a file, expected a folder")
    _against_inputs(out.option, path, inputs, folder=True)
    if not os.path.isdir(path):
        _probe(out.option, path, nearest)
        return
    _probe(out.option, path, _absolute(path))
    try:
        names = [n for n in os.listdir(path) if n != RECORD and not n.startswith(STAGE_PREFIX)]
    except OSError as exc:
        raise _refuse(out.option, path, f"cannot read the folder ({exc.strerror or exc})") from None
    if not names:
        return
    owned = owned_files(Path(path))
    ours = owned is not None or any(os.path.isfile(os.path.join(path, m)) for m in out.markers)
    if not ours and not force:
        markers = " or ".join(out.markers) or "record"
        raise _refuse(
            out.option,
            path,
            f"the folder exists and holds other files (no {markers} of an earlier run); pass --force to "
            "write into it (the other files are kept)",
        )
    if owned is None and ours:
        return  # an earlier run's folder from before the record: what it writes again is its own
    tops = {f.split("/", 1)[0] for f in owned or ()}
    for name in sorted(names):
        if name not in tops and any(fnmatch.fnmatchcase(name, p) for p in out.writes):
            raise _refuse(
                out.option,
                path,
                f"{name} would be written over and was not written by this tool; move it away or choose "
                "another folder",
            )


def check_outputs(
    inputs: Iterable[Path | str | None],
    outputs: Iterable[OutputFile | OutputFolder | None],
    force: bool = False,
) -> None:
    """Refuse, before any work, an output that is or holds an input, lies in an input folder, is the
    wrong kind, cannot be written, or is a folder of someone else's files (without ``force``);
    ``None`` entries (an option not given) are skipped."""
    resolved = [_Input(Path(p)) for p in inputs if p is not None and os.path.lexists(p)]
    for out in outputs:
        if isinstance(out, OutputFile):
            _check_file(out, resolved)
        elif isinstance(out, OutputFolder):
            _check_folder(out, resolved, force)


@contextmanager
def removed_on_storage_error(folder: Path) -> Iterator[None]:
    """What a command adds to its output ``folder`` is taken away again when writing fails (a full
    disk or quota mid-way, ``OSError``): the entries that were not there before, and the folder
    itself when the command made it. What was there before stays as it was; the error goes on."""
    existed = folder.is_dir()
    before = set(os.listdir(folder)) if existed else set()
    try:
        yield
    except OSError:
        if folder.is_dir() and not folder.is_symlink():
            for name in set(os.listdir(folder)) - before:
                entry = folder / name
                with suppress(OSError):
                    if entry.is_dir() and not entry.is_symlink():
                        shutil.rmtree(entry)
                    else:
                        entry.unlink()
            if not existed:
                with suppress(OSError):
                    folder.rmdir()
        raise
