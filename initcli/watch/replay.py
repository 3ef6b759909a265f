"""A recording through a :class:`~initcli.watch.monitor.Watcher`: a detection log with the
localiser's poses (``localiser`` records: ``bim-init bag2log --pose-topic``, or a bag read as
``bag2log`` reads it), replayed in time order with the decisions a live watch makes."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import Site
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.verify.params import VerificationParams
from initcli.core.watch.params import WatchParams
from initcli.io.log_records import DetectionLog, Localiser, Odom, Scan
from initcli.watch.monitor import Watcher
from initcli.watch.records import EventKind, WatchCheck, WatchEvent, WatchState

__all__ = ["EXIT_LOST", "EXIT_OK", "WatchResult", "watched_storey", "watch_log"]

EXIT_OK = 0  # never lost, or lost and recovered
EXIT_LOST = 1  # lost and not recovered


@dataclass
class WatchResult:
    storey: str
    events: list[WatchEvent]
    checks: list[WatchCheck]
    localiser: list[tuple[float, Pose2D]]  # the localiser's poses as recorded
    state: WatchState  # at the end
    travel: float  # m of odometry travel
    why_not_recovered: str = ""
    notes: list[str] = field(default_factory=list)

    @property
    def lost(self) -> bool:
        return self.state is WatchState.LOST

    @property
    def exit_code(self) -> int:
        return EXIT_LOST if self.lost else EXIT_OK

    def summary(self) -> str:
        lost = sum(e.kind is EventKind.LOST for e in self.events)
        found = sum(e.kind is EventKind.RECOVERED for e in self.events)
        if not lost:
            return f"never lost over {self.travel:.1f} m ({len(self.checks)} checks)"
        if self.lost:
            why = self.why_not_recovered or "no place yet"
            return f"lost {lost} time(s), recovered {found}; lost at the end: {why}"
        return f"lost {lost} time(s), recovered {found} ({self.travel:.1f} m, {len(self.checks)} checks)"

    def as_dict(self) -> dict[str, Any]:
        return {
            "events": [e.as_dict() for e in self.events],
            "storey": self.storey,
            "state": str(self.state),
            "travel": round(self.travel, 3),
            "summary": self.summary(),
            "exit_code": self.exit_code,
            "checks": [c.as_dict() for c in self.checks],
        }


def watched_storey(site: Site, storey: str | None) -> str:
    """The storey whose map the localiser tracks on: ``storey``, or the site's only storey with a map."""
    if storey is not None and storey != "auto":
        if site.storey(storey).grid is None:
            raise InputError(f"{site.root}: storey {storey!r} has no map to check a pose on")
        return storey
    mapped = [name for name, s in site.storeys.items() if s.grid is not None]
    if len(mapped) == 1:
        return mapped[0]
    if not mapped:
        raise InputError(f"{site.root}: no storey has a map to check a pose on")
    listed = ", ".join(repr(n) for n in mapped)
    raise InputError(
        f"{site.root}: {len(mapped)} storeys have maps ({listed}): name the localiser's with --storey"
    )


def check_recording(log: DetectionLog) -> None:
    """Refuse a log the watch cannot replay, before any work: no localiser pose, odometry or scan."""
    missing = [
        what
        for what, kind in (("localiser", Localiser), ("odom", Odom), ("scan", Scan))
        if not log.of_type(kind)
    ]
    if "localiser" in missing:
        raise InputError(
            f"{log.path}: no localiser pose (no 'localiser' record) to watch: record the localiser's"
            " topic (bag2log --pose-topic /amcl_pose, or tf for map -> odom)"
        )
    if missing:
        raise InputError(
            f"{log.path}: no {' or '.join(repr(m) for m in missing)} record: the watch needs both"
        )


def watch_log(
    log: DetectionLog,
    site: Site,
    storey: str | None = None,
    params: WatchParams | None = None,
    registration: RegistrationParams | None = None,
    verification: VerificationParams | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> WatchResult:
    """Replay ``log`` through a watcher of ``storey`` (module docstring)."""
    check_recording(log)
    name = watched_storey(site, storey)
    watcher = Watcher(site, name, params, registration, verification)
    total = len(log.records)
    for i, rec in enumerate(log.records):
        if isinstance(rec, Odom):
            watcher.odom(rec.t, rec.pose)
        elif isinstance(rec, Localiser):
            watcher.localiser(rec.t, rec.pose)
        elif isinstance(rec, Scan):
            angles = rec.angle_min + rec.angle_increment * np.arange(len(rec.ranges))
            ranges = np.array([math.nan if r is None else r for r in rec.ranges], dtype=float)
            watcher.scan(rec.t, angles, ranges, rec.range_max)
        if progress is not None and i % 200 == 0:
            progress(i, total)
    if progress is not None:
        progress(total, total)
    return WatchResult(
        name,
        watcher.events,
        watcher.checks,
        [(r.t, r.pose) for r in log.localiser],
        watcher.state,
        watcher.travel,
        watcher.why_not_recovered,
    )
