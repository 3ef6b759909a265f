"""The depth D of Eq. 1: the mean of the valid depth pixels in a window at the box centre (§3.3.1)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["window_depth"]


def window_depth(
    depth: np.ndarray, u: float, v: float, n: int = 2, min_depth: float = 0.0, max_depth: float = math.inf
) -> float | None:
    """Mean of the valid depths (finite, > 0, in [min_depth, max_depth]) in the (2n+1)^2 window at (u, v).

    This is D of Eq. 1 for a box centred on pixel (u, v); None when no pixel of the window is valid.
    """
    h, w = depth.shape[:2]
    cu, cv = int(math.floor(u)), int(math.floor(v))
    if not (0 <= cu < w and 0 <= cv < h):
        return None
    patch = depth[max(0, cv - n) : min(h, cv + n + 1), max(0, cu - n) : min(w, cu + n + 1)].astype(np.float64)
    ok = np.isfinite(patch) & (patch > 0) & (patch >= min_depth) & (patch <= max_depth)
    return float(patch[ok].mean()) if ok.any() else None  # Eq. 1: D, the window mean
