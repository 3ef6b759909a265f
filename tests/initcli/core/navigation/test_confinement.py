"""Loops and shuttling told from travelling (initcli.core.navigation.confinement)."""

from __future__ import annotations

import math

from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.confinement import ConfinementWatch, confined


def test_shuttling_is_told_from_travelling() -> None:
    trace: list[tuple[float, float, float]] = []
    hits = [
        confined(trace, t, Pose2D(5.0 * math.sin(t / 8.0), 0.0, 0.0), 150.0, 45.0, 8.0) for t in range(200)
    ]
    assert any(hits[140:])  # back and forth over 10 m for minutes
    trace.clear()
    hits = [confined(trace, t, Pose2D(0.5 * t, 0.0, 0.0), 150.0, 45.0, 8.0) for t in range(200)]
    assert not any(hits)  # a long straight drive


def test_watch_keeps_its_own_trace() -> None:
    watch = ConfinementWatch(45.0, 15.0, 2.5)
    circling = [
        watch.confined(float(t), Pose2D(2.0 * math.cos(t / 3), 2.0 * math.sin(t / 3), 0.0))
        for t in range(120)
    ]
    assert any(circling[60:])
