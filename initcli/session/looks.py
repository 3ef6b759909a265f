"""Turning in place: the initial look, a look on an open floor and the recovery rotation (§3.3.4),
how far the robot has turned, and when to look again or cross the floor (beyond the paper).

A look costs time, no distance: the camera sees what is behind the robot. Along a wall with open
space on the other side (a hall, a car park, an open-plan office) the camera looks along the
followed wall and the features across the floor stay out of its view, so the robot looks round
again every ``exploration.look_every`` metres without a new feature; after ``cross_after`` such
looks it drives across the floor (:meth:`initcli.session.escapes.Escapes.cross`).
"""

from __future__ import annotations

import math

import numpy as np

from initcli.config.session import ExplorationSection
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.navigation.bug_navigation import FloorCrossing
from initcli.core.navigation.feature_walls import toward_feature_wall
from initcli.core.navigation.wall_following import ScanView, open_beside
from initcli.drivers.base import SensorFrame
from initcli.session.escapes import Escapes

__all__ = ["Looks"]


class Looks:
    """How far the robot turned in the look or rotation under way, and the looks on open floors."""

    def __init__(self, exploration: ExplorationSection) -> None:
        self.settings = exploration
        self.full_turn = math.radians(exploration.turn)  # rad a look or a recovery rotation turns
        self.turned = 0.0  # rad turned since the look or recovery rotation began
        self.look_from = 0.0  # m of odometry travel at the last look or new feature
        self.count = 0  # looks begun (the initial one included)
        self.open_floor = False  # the look under way is one on an open floor, not the initial one
        self.fruitless = 0  # looks on an open floor ended since the last new feature or crossing
        self.feature_walls: list[np.ndarray] = []  # odom points where crossings to feature walls ended

    def begin(self) -> None:
        """A look (or the recovery rotation) starts turning."""
        self.turned = 0.0

    def moved(self, previous: Pose2D, now: Pose2D) -> None:
        """The robot moved from ``previous`` to ``now`` (odometry): count the turn."""
        self.turned += abs(float(wrap_angle(now.yaw - previous.yaw)))

    @property
    def done(self) -> bool:
        """Has the look or rotation under way turned all the way round?"""
        return self.turned >= self.full_turn

    def again(self, travel: float, scan: ScanView, side: int) -> bool:
        """Look round on the spot again (and start that look)? After ``look_every`` m of ``travel``
        without a new feature along a wall (``side`` +1 left, -1 right) with open space on the other
        side. In a corridor (see :func:`open_beside`) the camera already sees both walls ahead, and
        the robot drives on."""
        every = self.settings.look_every
        if every <= 0 or travel - self.look_from < every:
            return False
        if not open_beside(scan, side):
            return False
        self.look_from = travel
        self.begin()
        self.count += 1
        self.open_floor = True
        return True

    def new_feature(self, travel: float) -> None:
        """A new feature was confirmed at ``travel`` m: the next look is look_every m on."""
        self.look_from = travel
        self.fruitless = 0

    def cross(
        self,
        frame: SensorFrame,
        scan: ScanView,
        side: int,
        escapes: Escapes,
        travel: float,
        predicted: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
        path: np.ndarray | None = None,
    ) -> FloorCrossing | None:
        """A look on an open floor ended at ``travel`` m: after ``cross_after`` such looks since the
        last new feature (a look that found one counts as the first), drive across the floor
        (:meth:`Escapes.cross`), then follow the wall found there: from the façade of an open-plan
        office the doors of the rooms in the middle are out of the camera's reach, and looking again
        from the same wall finds nothing. The next look comes look_every m after the crossing's
        reach. With ``predicted`` (the hypotheses' unseen features, :func:`unseen_features`) and
        ``exploration.feature_walls``, every such look first tries the wall that holds them
        (:func:`toward_feature_wall`; ``path``: odom points driven so far). The crossing started, or None."""
        self.fruitless += 1
        crossing = None
        if predicted is not None and self.settings.feature_walls:
            been = frame.odom.apply_inverse(np.array(self.feature_walls).reshape(-1, 2))
            passed = None if path is None else frame.odom.apply_inverse(np.asarray(path).reshape(-1, 2))
            way = toward_feature_wall(scan, *predicted, been=been, passed=passed)
            if way is not None:
                crossing = escapes.cross(frame, scan, side, way[:2])
                end = frame.odom.apply(way[1] * np.array([math.cos(way[0]), math.sin(way[0])]))
                self.feature_walls.append(end)
        after = self.settings.cross_after
        if crossing is None and (after <= 0 or self.fruitless < after):
            return None
        crossing = crossing or escapes.cross(frame, scan, side)
        if crossing is None:
            return None
        self.fruitless = 0
        self.look_from = travel + crossing.reach
        return crossing
