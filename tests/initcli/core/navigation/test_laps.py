"""initcli.core.navigation.laps: a lap of the odometry path, and the area it encloses."""

from __future__ import annotations

import math

from initcli.core.navigation.laps import Lap, LapWatch


def drive(watch: LapWatch, points: list[tuple[float, float]]) -> Lap | None:
    travel, lap = 0.0, None
    for (x0, y0), (x1, y1) in zip(points[:-1], points[1:], strict=True):
        steps = max(1, int(math.hypot(x1 - x0, y1 - y0) / 0.1))
        for k in range(1, steps + 1):
            x, y = x0 + (x1 - x0) * k / steps, y0 + (y1 - y0) * k / steps
            travel += math.hypot(x1 - x0, y1 - y0) / steps
            if watch.add(travel, x, y) and lap is None:
                lap = watch.lap()
    return lap


def test_a_lap_round_a_room_encloses_the_room_and_a_small_circle_little() -> None:
    room = drive(LapWatch(), [(0.0, 0.0), (3.6, 0.0), (3.6, 4.6), (0.0, 4.6), (0.0, 0.0), (1.0, 0.0)])
    assert room is not None and abs(room.enclosed - 3.6 * 4.6) < 2.0 and room.length > 14.0
    circle = [(1.3 * math.cos(a / 20 * 2 * math.pi), 1.3 * math.sin(a / 20 * 2 * math.pi)) for a in range(25)]
    small = drive(LapWatch(), circle)
    assert small is not None and small.enclosed < 6.0
    assert drive(LapWatch(), [(0.0, 0.0), (20.0, 0.0)]) is None  # a straight drive closes no lap
