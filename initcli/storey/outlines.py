"""Outlines of a storey's elements as line segments (x1, y1, x2, y2) for ray casting and occlusion."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["box_edges", "box_ring", "closed_ring", "polygon_edges"]


def polygon_edges(ring: np.ndarray) -> np.ndarray:
    """(n, 2) closed ring -> (n-1, 4) segments x1, y1, x2, y2."""
    ring = np.asarray(ring, dtype=float)
    return np.column_stack([ring[:-1], ring[1:]])


def closed_ring(points: object) -> np.ndarray:
    """(n, 2) points of an outline, with the first repeated at the end when it is not already."""
    ring = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(ring) > 1 and not np.array_equal(ring[0], ring[-1]):
        ring = np.vstack([ring, ring[:1]])
    return ring


def box_edges(cx: float, cy: float, half_w: float, half_h: float, yaw: float = 0.0) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    corners = np.array(
        [[-half_w, -half_h], [half_w, -half_h], [half_w, half_h], [-half_w, half_h], [-half_w, -half_h]]
    )
    rot = corners @ np.array([[c, s], [-s, c]]) + [cx, cy]
    return polygon_edges(rot)


def box_ring(centre: np.ndarray, along: np.ndarray, half_length: float, half_depth: float) -> np.ndarray:
    """The closed (5, 2) ring of a rectangle: ``half_length`` either side of ``centre`` along the unit
    vector ``along``, ``half_depth`` across it."""
    across = np.array([-along[1], along[0]])
    c = [
        centre - along * half_length - across * half_depth,
        centre + along * half_length - across * half_depth,
        centre + along * half_length + across * half_depth,
        centre - along * half_length + across * half_depth,
    ]
    return np.vstack([c, c[:1]])
