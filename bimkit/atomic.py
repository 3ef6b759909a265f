"""Write outputs so that a failure never leaves half a file or half a folder behind."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["replace_directory", "staged_directory", "write_bytes_atomic", "write_text_atomic"]


@contextmanager
def staged_directory(target: Path) -> Iterator[Path]:
    """Yield a fresh hidden folder beside ``target``; on success it replaces ``target`` whole.

    The replacement is two renames (the old folder aside, the new one in place), so ``target`` is
    always either the old folder or the new one. On any exit other than success -- an exception,
    Ctrl-C (KeyboardInterrupt), a failing rename -- the staging folder is removed and ``target`` is
    as it was. Callers check ``target`` first (:func:`bimkit.checks.check_output_dir`): a file,
    or a folder some other tool wrote, is refused before any work starts.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        yield stage
        replace_directory(stage, target)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def replace_directory(stage: Path, target: Path) -> None:
    """Put the folder ``stage`` in the place of ``target`` (absent, or a folder); on a failure
    ``target`` is restored and the error raised."""
    if not target.exists():
        os.replace(stage, target)
        return
    if not target.is_dir() or target.is_symlink():
        raise NotADirectoryError(f"{target} is not a folder")
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
    old.rmdir()
    os.replace(target, old)
    try:
        os.replace(stage, target)
    except BaseException:
        os.replace(old, target)
        raise
    shutil.rmtree(old, ignore_errors=True)


def write_text_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
