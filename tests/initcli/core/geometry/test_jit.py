"""initcli.core.geometry.jit: compiled loops, cached on disk where numba finds a place for the cache."""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
import pytest

from initcli.core.geometry import jit


def _total(values: np.ndarray) -> float:
    out = 0.0
    for v in values:
        out += v
    return out


def test_compiled_loops_compute_what_python_does() -> None:
    values = np.linspace(0.1, 3.0, 17)
    assert jit.compiled(_total)(values) == _total(values)


def test_without_a_writable_cache_the_loop_is_compiled_per_process(monkeypatch: pytest.MonkeyPatch) -> None:
    """numba refuses ``cache=True`` where it can write no cache (a read-only site-packages and no
    user cache directory): the loop is compiled without one instead of failing the import."""
    plain = numba.njit
    asked: list[bool] = []

    def njit(*args: Any, **kwargs: Any) -> Any:
        asked.append(bool(kwargs.get("cache")))
        if kwargs.get("cache"):
            raise RuntimeError("cannot cache function '_total': no locator available for file 'x.py'")
        return plain(*args, **kwargs)

    monkeypatch.setattr(numba, "njit", njit)
    fn = jit.compiled(_total)
    assert asked == [True, False]
    assert fn(np.arange(5.0)) == 10.0


def test_without_numba_the_loop_runs_as_python(monkeypatch: pytest.MonkeyPatch) -> None:
    """numba is the [fast] extra: without it, compiled() hands back the function itself."""
    monkeypatch.setattr(jit, "AVAILABLE", False)
    assert jit.compiled(_total) is _total
