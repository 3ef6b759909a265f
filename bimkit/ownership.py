"""Which existing file a command may write over: only one it wrote itself, told by its content
(:class:`bimkit.outputs.OutputFile`'s ``owned``). A plot carries matplotlib's name in its metadata,
an ONNX model its producer, a JSON document its format; a file that cannot tell (a recording) is
never written over."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

__all__ = ["drawn_by_matplotlib", "json_of_format", "never_written_over", "starts_with_marker"]

HEAD = 65536  # bytes read from the start of a file (and its end, for a PDF's trailer)


def _ends(path: Path) -> bytes:
    try:
        with open(path, "rb") as f:
            head = f.read(HEAD)
            f.seek(0, 2)
            size = f.tell()
            f.seek(max(size - HEAD, len(head)))
            return head + f.read(HEAD)
    except OSError:
        return b""


def drawn_by_matplotlib(path: Path) -> bool:
    """A PNG, PDF or SVG whose metadata names matplotlib (what every plot of this tool is drawn with)."""
    return b"matplotlib" in _ends(Path(path)).lower()


def starts_with_marker(marker: bytes, within: int = 512) -> Callable[[Path], bool]:
    """A file whose first ``within`` bytes hold ``marker`` (an ONNX model's producer name)."""

    def owned(path: Path) -> bool:
        return marker in _ends(Path(path))[:within]

    return owned


def json_of_format(fmt: str) -> Callable[[Path], bool]:
    """A JSON document whose ``format`` is ``fmt``."""

    def owned(path: Path) -> bool:
        try:
            doc = json.loads(Path(path).read_bytes()[: 16 * 1024 * 1024])
        except (OSError, ValueError):
            return False
        return isinstance(doc, dict) and doc.get("format") == fmt

    return owned


def never_written_over(path: Path) -> bool:
    """A file this tool cannot tell it wrote (a recording): never written over."""
    return False
