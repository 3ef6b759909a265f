"""Compiled inner loops: :func:`compiled` is numba's ``njit`` with the machine code cached on disk.

Only loops whose numpy form spends its time building index arrays for a few thousand scalar
operations go through here (the lidar's ray/segment pairs). A compiled loop computes the same
float64 expressions in the same order as its numpy form -- numba compiles without fast-math, so no
reassociation and no fused multiply-add -- and the tests compare the two bit for bit. The cache
lives beside the module (``__pycache__``) or, where that is read-only (a wheel in a system
site-packages), in the user's cache directory; with neither, the loop is compiled once per process.

numba is the ``[fast]`` extra, not a core dependency: without it a loop runs as the Python it is
written in, with the same results, more slowly (a simulated session without the camera takes
about 1.6 times as long).
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from typing import Any, TypeVar, cast

__all__ = ["AVAILABLE", "compiled"]

F = TypeVar("F", bound=Callable[..., Any])

AVAILABLE = importlib.util.find_spec("numba") is not None  # the [fast] extra is installed


def compiled(fn: F) -> F:
    """``fn`` compiled in nopython mode, cached on disk where a cache directory can be written;
    ``fn`` itself where numba is not installed."""
    if not AVAILABLE:
        return fn
    import numba

    try:
        return cast(F, numba.njit(cache=True)(fn))
    except RuntimeError:  # numba: "cannot cache function ...: no locator available"
        return cast(F, numba.njit(fn))
