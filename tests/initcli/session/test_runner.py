"""The session loop's shuttle detection: shuttling is told from travelling."""

from __future__ import annotations

import math

from initcli.core.geometry import Pose2D
from initcli.drivers.base import SensorFrame
from initcli.session.runner import confined


def frame_at(t: float, x: float, y: float) -> SensorFrame:
    return SensorFrame(t, Pose2D(x, y, 0.0))


def test_shuttling_is_told_from_travelling():
    trace: list[tuple[float, float, float]] = []
    hits = [confined(trace, frame_at(t, 5.0 * math.sin(t / 8.0), 0.0), 150.0, 45.0, 8.0) for t in range(200)]
    assert any(hits[140:])  # back and forth over 10 m for minutes
    trace.clear()
    hits = [confined(trace, frame_at(t, 0.5 * t, 0.0), 150.0, 45.0, 8.0) for t in range(200)]
    assert not any(hits)  # a long straight drive
