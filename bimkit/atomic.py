"""Write outputs so that a failure never leaves half a file or half a folder behind, and so that a
folder is never emptied of files the tool did not write.

An output folder carries a record of the files the tool wrote into it (:data:`RECORD`, a hidden
JSON file). Replacing the folder's content (:func:`staged_directory`) removes only those: a file
the tool did not write -- the user's notes, the IFC model the site was extracted from -- is kept
where it is, and a new output that would land on such a file is refused (nothing is written). A
folder from before the record existed counts as the tool's where it holds the tool's marker file
(``site.json``, ``summary.json``): the files the new run writes again are then replaced, the rest
kept. Tools that write into a folder bit by bit (``bim-init eval``, ``survey``) add what they
wrote to the record with :func:`claim`.
"""

from __future__ import annotations

import contextlib
import fnmatch
import json
import os
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path, PurePosixPath

from bimkit.errors import InputError

__all__ = [
    "RECORD",
    "claim",
    "owned_files",
    "replace_directory",
    "staged_directory",
    "write_bytes_atomic",
    "write_text_atomic",
]

RECORD = ".bim-outputs.json"  # in an output folder: {"files": [relative paths the tool wrote]}
STAGE_PREFIX = ".bim-stage."  # a folder being written (removed on any failure or interrupt)
_OLD_PREFIX = ".bim-old."  # the replaced files, between the two steps of a replacement


def _is_machinery(name: str) -> bool:
    return name == RECORD or name.startswith((STAGE_PREFIX, _OLD_PREFIX))


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _files(root: Path) -> list[str]:
    """Every file (and symbolic link) under ``root``, as sorted relative POSIX paths."""
    found: list[str] = []
    for base, dirs, names in os.walk(root):
        rel = Path(base).relative_to(root)
        for name in names + [d for d in dirs if os.path.islink(os.path.join(base, d))]:
            found.append((rel / name).as_posix())
    return sorted(found)


def _safe_relative(entry: object) -> str | None:
    """A record entry as a relative path inside the folder, or None (absolute, ``..``, not text)."""
    if not isinstance(entry, str) or not entry:
        return None
    path = PurePosixPath(entry)
    if path.is_absolute() or ".." in path.parts or _is_machinery(path.parts[0]):
        return None
    return path.as_posix()


def owned_files(folder: Path) -> set[str] | None:
    """The files the record of ``folder`` says the tool wrote (None: no record). A record that
    cannot be read owns nothing: the safe side (files are kept, a clash is refused)."""
    path = Path(folder) / RECORD
    if not path.is_file():
        return None
    from bimkit.documents import read_json  # bounded reading; no import cycle at module load

    try:
        doc = read_json(path, "an output record")
    except InputError:
        return set()
    entries = doc.get("files") if isinstance(doc, dict) else None
    if not isinstance(entries, list):
        return set()
    return {p for p in (_safe_relative(e) for e in entries) if p is not None}


def _write_record(folder: Path, files: Iterable[str]) -> None:
    write_text_atomic(folder / RECORD, json.dumps({"files": sorted(set(files))}, indent=1) + "\n")


def claim(folder: Path, patterns: Iterable[str]) -> None:
    """Add to the record of ``folder`` the entries at its top level whose names match ``patterns``
    (fnmatch; a folder with every file in it): what a tool that writes into a folder bit by bit
    wrote there. :func:`bimkit.outputs.check_outputs` refused, before the work, a file of someone
    else that matches."""
    folder = Path(folder)
    owned = set(owned_files(folder) or ())
    wanted = tuple(patterns)
    for entry in sorted(os.listdir(folder)) if folder.is_dir() else []:
        if _is_machinery(entry) or not any(fnmatch.fnmatchcase(entry, p) for p in wanted):
            continue
        path = folder / entry
        if path.is_dir() and not path.is_symlink():
            owned.update(f"{entry}/{f}" for f in _files(path))
        else:
            owned.add(entry)
    _write_record(folder, owned)


__all__ = ["replace_directory", "staged_directory", "write_bytes_atomic", "write_text_atomic"]


@contextmanager
def _signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM wait while a replacement moves files: they are noted and delivered to
    their handlers (KeyboardInterrupt, :class:`bimkit.cli.Terminated`) right after. Python runs
    signal handlers in the main thread whichever thread the kernel picked, so the handlers are
    swapped, not the thread's signal mask."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    noted: list[int] = []
    held = (signal.SIGINT, signal.SIGTERM)
    previous = {s: signal.signal(s, lambda signum, frame: noted.append(signum)) for s in held}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler if handler is not None else signal.SIG_DFL)
        for number in dict.fromkeys(noted):
            handler = previous[signal.Signals(number)]
            if callable(handler):
                handler(number, None)
            elif handler != signal.SIG_IGN:
                os.kill(os.getpid(), number)  # the default action, now that the files are in place


@contextmanager
def staged_directory(target: Path, markers: Iterable[str] = ()) -> Iterator[Path]:
    """Yield a fresh hidden folder to write into; on success its files take their place in ``target``.

    ``target`` absent: the stage (beside it) is renamed into place, whole. ``target`` a folder: the
    stage is made inside it and :func:`replace_directory` moves the new files in, removing only the
    files the tool wrote there before. On any exit other than success -- an exception, Ctrl-C
    (KeyboardInterrupt), SIGTERM (turned into one by :func:`bimkit.cli.run_cli`), a refused clash --
    the stage is removed and ``target`` is as it was. Callers check ``target`` before any work
    starts (:func:`bimkit.outputs.check_outputs`).
    """
    target = Path(os.path.realpath(target))  # a link to a folder: the folder it names
    if target.is_dir():
        stage = Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=target))
    else:
        target.parent.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=f"{STAGE_PREFIX}{target.name}.", dir=target.parent))
    try:
        yield stage
        replace_directory(stage, target, markers)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def replace_directory(stage: Path, target: Path, markers: Iterable[str] = ()) -> None:
    """Put the files of the folder ``stage`` in ``target`` (absent, or a folder), removing the files
    the tool wrote there before and keeping every other one; on a failure ``target`` is restored
    and the error raised. A new file that would replace a file the tool did not write is an
    :class:`InputError` (nothing changed)."""
    stage, target = Path(stage), Path(os.path.abspath(target))
    new = [f for f in _files(stage) if not _is_machinery(f.split("/", 1)[0])]
    if not os.path.lexists(target):
        _write_record(stage, new)
        os.chmod(stage, 0o777 & ~_umask())
        os.replace(stage, target)
        return
    if not target.is_dir() or target.is_symlink():
        raise NotADirectoryError(f"{target} is not a folder")
    owned = owned_files(target)
    if owned is None:  # a folder from before the record: the tool's where its marker is in it
        legacy = any((target / m).is_file() for m in markers)
        owned = {f for f in new if os.path.lexists(target / f)} if legacy else set()
    clashes = [f for f in new if _clashes(target, f, owned)]
    if clashes:
        raise InputError(
            f"{target / clashes[0]}: would be replaced, but was not written by this tool; move it away "
            "or choose another output folder (nothing was written)"
        )
    with _signals_held():
        old = Path(tempfile.mkdtemp(prefix=_OLD_PREFIX, dir=target))
        moved_old: list[str] = []
        moved_new: list[str] = []
        try:
            for f in sorted(owned):
                src = target / f
                if not os.path.lexists(src) or (src.is_dir() and not src.is_symlink()):
                    continue
                (old / f).parent.mkdir(parents=True, exist_ok=True)
                os.replace(src, old / f)
                moved_old.append(f)
            for f in new:
                (target / f).parent.mkdir(parents=True, exist_ok=True)
                os.replace(stage / f, target / f)
                moved_new.append(f)
            _write_record(target, new)
        except BaseException:
            for f in reversed(moved_new):
                with contextlib.suppress(OSError):
                    os.replace(target / f, stage / f)
            for f in reversed(moved_old):
                with contextlib.suppress(OSError):
                    os.replace(old / f, target / f)
            raise
        finally:
            shutil.rmtree(old, ignore_errors=True)
        _prune(target, set(moved_old) - set(new))


def _clashes(target: Path, rel: str, owned: set[str]) -> bool:
    """Whether writing ``rel`` into ``target`` would replace something the tool did not write."""
    parts = PurePosixPath(rel).parts
    for k in range(1, len(parts)):  # a file where the new file needs a folder
        above = target.joinpath(*parts[:k])
        if os.path.lexists(above) and not above.is_dir() and "/".join(parts[:k]) not in owned:
            return True
    path = target / rel
    return os.path.lexists(path) and (rel not in owned or (path.is_dir() and not path.is_symlink()))


def _prune(target: Path, removed: set[str]) -> None:
    """Remove the folders that the removal of the tool's old files left empty (never ``target``)."""
    for f in sorted(removed, key=lambda p: -p.count("/")):
        folder = (target / f).parent
        while folder != target and target in folder.parents:
            try:
                folder.rmdir()
            except OSError:
                break
            folder = folder.parent


def write_text_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename."""
    if not isinstance(text, str):
        raise TypeError(f"expected text, got {type(text).__name__}")
    write_bytes_atomic(path, text.encode("utf-8"))


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
