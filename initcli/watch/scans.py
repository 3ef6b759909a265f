"""The recent scans the watch keeps: every beam, one scan per few centimetres of travel or degrees
of turn (a 40 Hz lidar standing still adds nothing), over the last metres the checks and a
re-initialisation read."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from initcli.core.lidar.scan_fit import BeamEnds, ScanSample

__all__ = ["RecentScans", "check_beams"]

KEEP_STEP_M = 0.05  # m of travel between two kept scans ...
KEEP_TURN = math.radians(3.0)  # ... or this much turn
CHECK_BEAMS = 180  # beams per scan the pose check reads at most (every n-th)
CHECK_POINTS = 3000  # beam ends a pose check reads at most (evenly picked)


def check_beams(scans: list[ScanSample]) -> BeamEnds:
    """The beam ends of ``scans``, every n-th beam so that each reads at most CHECK_BEAMS."""
    return BeamEnds.of([s.thinned(max(1, len(s.ranges) // CHECK_BEAMS)) for s in scans])


@dataclass
class RecentScans:
    """Scans in the odometry frame with the travel at each; those older than ``kept_m`` dropped."""

    kept_m: float
    scans: list[ScanSample] = field(default_factory=list)
    travel: list[float] = field(default_factory=list)
    times: list[float] = field(default_factory=list)

    def add(self, t: float, scan: ScanSample, travel: float) -> bool:
        """Keep ``scan`` unless the robot has hardly moved since the last kept one; True if kept."""
        if self.scans:
            last = self.scans[-1].odom
            moved = travel - self.travel[-1]
            turned = abs(math.remainder(scan.odom.yaw - last.yaw, math.tau))
            if moved < KEEP_STEP_M and turned < KEEP_TURN:
                return False
        self.scans.append(scan)
        self.travel.append(travel)
        self.times.append(t)
        old = next((i for i, d in enumerate(self.travel) if travel - d <= self.kept_m), len(self.travel) - 1)
        if old:
            del self.scans[:old], self.travel[:old], self.times[:old]
        return True

    def since(self, travel: float) -> list[tuple[float, ScanSample, float]]:
        """(t, scan, travel) of the kept scans from ``travel`` m on."""
        return [(t, s, d) for t, s, d in zip(self.times, self.scans, self.travel, strict=True) if d >= travel]

    def check_ends(self, metres: float) -> BeamEnds | None:
        """The beam ends of the last ``metres`` of travel for a pose check (None: no scan)."""
        if not self.scans:
            return None
        now = self.travel[-1]
        chosen = [s for s, d in zip(self.scans, self.travel, strict=True) if now - d <= metres]
        ends = check_beams(chosen)
        if len(ends.xy) <= CHECK_POINTS:
            return ends
        keep = np.linspace(0, len(ends.xy) - 1, CHECK_POINTS).astype(np.intp)
        origins = ends.beam_origins()[keep]
        # one "scan" per point: the origins stay exact for the through-wall test
        return BeamEnds(ends.last, ends.xy[keep], np.ones(len(keep)), origins)
