"""The storey and settings a session recorded in its log's meta record, and ``bim-init match``
taking them back: a session's log then replays to the session's verdict and pose with no option
given (an option the user gives wins).

``settings`` holds ``matching`` (the :class:`~initcli.config.matching.MatchOptions` fields the
command takes, but ``storey``, ``top``, ``skip_bad`` and ``registration``) and ``registration``
(every :class:`~initcli.core.lidar.registration_params.RegistrationParams` field, ``enabled`` for
the command's ``--registration``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection
from dataclasses import dataclass
from typing import Any

from bimkit.errors import InputError
from bimkit.settings import check_ranges
from initcli.config.matching import MatchOptions
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.io.log_records import Meta

__all__ = ["NOT_RECORDED", "Recorded", "recorded_settings", "session_meta_settings"]

# MatchOptions fields that are not the session's matching: how the command reads and shows
NOT_RECORDED = frozenset({"storey", "top", "skip_bad", "registration"})


def session_meta_settings(options: MatchOptions, registration: RegistrationParams) -> dict[str, Any]:
    """The ``settings`` of a session's meta record: what it matched and registered with."""
    matching = {
        f.name: getattr(options, f.name) for f in dataclasses.fields(options) if f.name not in NOT_RECORDED
    }
    return {"matching": matching, "registration": dataclasses.asdict(registration)}


@dataclass(frozen=True)
class Recorded:
    """The options of a match with what the log recorded for those not given, and the note saying so."""

    options: MatchOptions
    registration: RegistrationParams
    note: str | None  # None: the log recorded nothing that was used


def recorded_settings(
    meta: Meta | None, options: MatchOptions, given: Collection[str], where: str
) -> Recorded:
    """``options`` with the storey and settings ``meta`` recorded for every option not in ``given``
    (the :class:`MatchOptions` field names the user gave; ``storey`` for ``--storey``). ``where``:
    the log's name for the messages. A log without them (one not written by a session, or one
    written before they were) leaves ``options`` as they are, with no note."""
    registration = RegistrationParams(enabled=options.registration)
    if meta is None or (meta.storey is None and meta.settings is None):
        return Recorded(options, registration, None)
    changes: dict[str, Any] = {}
    if meta.storey is not None and "storey" not in given:
        changes["storey"] = meta.storey
    settings = meta.settings or {}
    matching = settings.get("matching") or {}
    names = {f.name for f in dataclasses.fields(MatchOptions)} - NOT_RECORDED
    changes.update({k: v for k, v in matching.items() if k in names and k not in given})
    recorded_registration = {
        k: v
        for k, v in (settings.get("registration") or {}).items()
        if k in {f.name for f in dataclasses.fields(RegistrationParams)}
    }
    if "registration" in given:
        recorded_registration["enabled"] = options.registration
    elif "enabled" in recorded_registration:
        changes["registration"] = recorded_registration["enabled"]
    try:
        options = dataclasses.replace(options, **changes)
        options.validate()
        registration = RegistrationParams(**{**dataclasses.asdict(registration), **recorded_registration})
        check_ranges(registration, lambda name: f"settings.registration.{name}")
    except (TypeError, ValueError, InputError) as exc:
        raise InputError(f"{where}: the settings its meta record holds are not valid ({exc})") from None
    settled = bool(set(changes) - {"storey"} or recorded_registration)
    if "storey" in changes:
        said = f"storey {changes['storey']}" + (" and settings" if settled else "")
    elif settled:
        said = "settings"
    else:
        return Recorded(options, registration, None)
    every = meta.storey is None and "storey" not in given
    return Recorded(
        options,
        registration,
        f"{said} from the session's log" + ("; every storey searched, as it did" if every else ""),
    )
