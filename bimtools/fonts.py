"""Fonts for the pictures (preview_, survey_, report.png): text in any script a storey name uses.

matplotlib's bundled DejaVu Sans has Latin, Greek and Cyrillic but no CJK. No font is shipped with
the project: :func:`font_families` lists DejaVu Sans first and then any CJK family installed on this
machine (Noto Sans CJK, Source Han Sans, WenQuanYi, Droid Sans Fallback, ...); matplotlib (>= 3.6)
falls back along that list glyph by glyph. :func:`put_text` draws such text into an OpenCV image
(OpenCV's own Hershey fonts are ASCII only) the same way, a font per character.
Without a CJK font installed, CJK characters show as the font's missing-glyph box, never as "?".
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import ParamSpec, TypeVar

import numpy as np

__all__ = ["CJK_FAMILIES", "font_families", "font_paths", "put_text", "unicode_fonts"]

_P = ParamSpec("_P")
_R = TypeVar("_R")

CJK_FAMILIES = (
    "Noto Sans CJK JP",
    "Noto Sans CJK SC",
    "Noto Sans CJK TC",
    "Noto Sans CJK KR",
    "Source Han Sans",
    "Noto Sans JP",
    "Noto Sans SC",
    "WenQuanYi Zen Hei",
    "WenQuanYi Micro Hei",
    "Droid Sans Fallback",
    "IPAGothic",
    "IPAexGothic",
    "TakaoGothic",
    "NanumGothic",
    "AR PL UMing CN",
    "Microsoft YaHei",
    "SimHei",
    "MS Gothic",
    "Malgun Gothic",
    "PingFang SC",
    "Hiragino Sans",
    "Arial Unicode MS",
)


@functools.cache
def _installed() -> dict[str, str]:
    """Family name -> font file of every font matplotlib knows on this machine."""
    from matplotlib import font_manager

    found: dict[str, str] = {}
    for entry in font_manager.fontManager.ttflist:
        found.setdefault(entry.name, entry.fname)
    return found


@functools.cache
def font_families() -> tuple[str, ...]:
    """``font.family`` for matplotlib: DejaVu Sans, then the CJK families installed here."""
    installed = _installed()
    return ("DejaVu Sans", *(f for f in CJK_FAMILIES if f in installed))


def unicode_fonts(draw: Callable[_P, _R]) -> Callable[_P, _R]:
    """Run a matplotlib drawing function with ``font.family`` = :func:`font_families`."""

    @functools.wraps(draw)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        import matplotlib

        with matplotlib.rc_context({"font.family": list(font_families())}):
            return draw(*args, **kwargs)

    return wrapper


@functools.cache
def font_paths() -> tuple[str, ...]:
    """The files of :func:`font_families`, in order (DejaVu Sans: matplotlib's own copy)."""
    import matplotlib

    dejavu = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
    installed = _installed()
    return (str(dejavu), *(installed[f] for f in font_families()[1:]))


@functools.cache
def _has_glyph(path: str, char: str) -> bool:
    return _ft2(path).get_char_index(ord(char)) != 0


@functools.cache
def _ft2(path: str):  # type: ignore[no-untyped-def]
    from matplotlib.ft2font import FT2Font

    return FT2Font(path)


@functools.cache
def _pil_font(path: str, size: int):  # type: ignore[no-untyped-def]
    from PIL import ImageFont

    return ImageFont.truetype(path, size)


def _runs(text: str) -> list[tuple[str, str]]:
    """``text`` cut into runs of one font each: the first of :func:`font_paths` with the glyph."""
    paths = font_paths()
    runs: list[tuple[str, str]] = []
    for char in text:
        path = next((p for p in paths if char.isspace() or _has_glyph(p, char)), paths[0])
        if runs and runs[-1][0] == path:
            runs[-1] = (path, runs[-1][1] + char)
        else:
            runs.append((path, char))
    return runs


def put_text(image: np.ndarray, text: str, org: tuple[int, int], size: int, colour: tuple[int, ...]) -> None:
    """Draw ``text`` into a BGR ``image`` with its baseline's left end at ``org`` (as cv2.putText)."""
    from PIL import Image, ImageDraw

    # a name that is not valid UTF-8 (a lone surrogate from a file name) draws as U+FFFD
    text = text.encode("utf-8", "replace").decode("utf-8")
    pil = Image.fromarray(np.ascontiguousarray(image[..., ::-1]))
    draw = ImageDraw.Draw(pil)
    x, y = org
    rgb = tuple(int(c) for c in colour[:3][::-1])
    for path, run in _runs(text):
        font = _pil_font(path, size)
        draw.text((x, y), run, font=font, fill=rgb, anchor="ls")
        x += int(round(draw.textlength(run, font=font)))
    image[...] = np.asarray(pil)[..., ::-1]
