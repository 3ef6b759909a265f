"""The session's states (§3.3.4) and its transitions: each one kept in the result and written to the
detection log as a ``state`` record, with why the session stays in its state noted there too."""

from __future__ import annotations

from enum import StrEnum

from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.drivers.base import SensorFrame
from initcli.io.detection_log import State
from initcli.session.perception import Perception
from initcli.session.result import SessionResult

__all__ = ["SessionState", "StateLog"]


class SessionState(StrEnum):
    """A state of the session; its value is the word its ``state`` records carry."""

    EXPLORE = "explore"  # random exploration: wall following
    LOOK = "look"  # turning once on the spot (the initial look, one on an open floor)
    ACTIVE = "active"  # active exploration toward a target (exploration.active)
    RECOVERY = "recovery"  # turning in place after a fruitless target
    COARSE = "coarse"  # a unique match claimed (also the stage of the checks of a claim)
    FINE = "fine"  # fine tuning (also the stage of the final pose's checks)
    DONE = "done"
    FAILED = "failed"

    @property
    def turning(self) -> bool:
        """Does the robot turn in place in this state (a look, the recovery rotation)?"""
        return self in (SessionState.LOOK, SessionState.RECOVERY)


class StateLog:
    """The state the session is in; every transition goes to ``result.states`` and the log."""

    def __init__(self, perception: Perception, result: SessionResult) -> None:
        self.perception = perception
        self.result = result
        self.now = SessionState.EXPLORE

    def enter(self, t: float, state: SessionState, **data: object) -> None:
        """The session goes to ``state`` at ``t`` (``data``: what its record says besides)."""
        self.now = state
        self.result.states.append((t, state))
        self.perception.write(State(round(t, 3), {"state": state, **data}))

    def note(self, t: float, why: str) -> None:
        """Log why the session stays in its state."""
        self.perception.write(State(round(t, 3), {"state": self.now, "why": why}))

    def explore(self, t: float, why: str) -> None:
        """Back to random exploration for ``why``, unless exploring already."""
        if self.now != SessionState.EXPLORE:
            self.enter(t, SessionState.EXPLORE, why=why)

    def fail(
        self,
        frame: SensorFrame,
        reason: str,
        distance: float,
        confirmed: list[ConfirmedFeature],
        **data: object,
    ) -> None:
        """The session ends without a pose for ``reason`` (``distance`` m driven, ``confirmed``
        features seen; ``data``: what its record says besides)."""
        self.enter(frame.t, SessionState.FAILED, reason=reason, **data)
        self.result.failed(reason, frame.truth, frame.t, distance, confirmed)
