"""The session's lidar submap registration (beyond the paper; ``registration:`` settings): with no
camera claim, every ``registration.every`` m of travel from ``registration.min_travel`` on, the
scans of the last ``registration.window`` m are registered over every storey's map
(:func:`initcli.core.registration.register`); a unique registration becomes a hypothesis that the
claim checks judge as they judge a camera claim (:meth:`initcli.session.claims.ClaimChecks.registered`)
before the session fine-tunes it.
"""

from __future__ import annotations

from bimtools.site.load import Site
from initcli.core.geometry import Pose2D
from initcli.core.particle_filter import likelihood_field
from initcli.core.registration import Registration, RegistrationMap, register
from initcli.core.registration_settings import RegistrationParams
from initcli.core.scan_fit import BeamEnds, ScanSample
from initcli.match.pipeline import Hypothesis
from initcli.match.verify import PathEvidence

__all__ = ["DECIDED_BY_REGISTRATION", "SubmapRegistration", "registered_hypothesis"]

DECIDED_BY_REGISTRATION = "lidar registration"  # summary.json's decided_by for such a claim


class SubmapRegistration:
    """When to register, and the storeys' maps prepared for it (once, on the first attempt)."""

    def __init__(self, params: RegistrationParams, site: Site, storey: str | None, tolerance: float) -> None:
        self.params = params
        self.site = site
        self.storey = storey  # None: every storey
        self.tolerance = tolerance  # verification.scan_tolerance
        self.next_at = params.min_travel  # m of travel of the next attempt
        self.attempts = 0
        self._maps: list[RegistrationMap] | None = None

    def due(self, travel: float) -> bool:
        return self.params.enabled and travel >= self.next_at

    def maps(self) -> list[RegistrationMap]:
        if self._maps is None:
            names = [self.storey] if self.storey is not None else list(self.site.storeys)
            self._maps = [
                RegistrationMap(name, grid, likelihood_field(grid))
                for name in names
                if (grid := self.site.storeys[name].grid) is not None
            ]
        return self._maps

    def attempt(self, path: PathEvidence, travel: float) -> tuple[Registration, Pose2D | None]:
        """Register the submap of the recent path: the outcome, and the odom pose of the submap's last
        scan (a candidate's transform, odom -> BIM, is its pose times that pose's inverse; None
        without scans)."""
        self.next_at = travel + self.params.every
        self.attempts += 1
        scans, _ = path.along(self.params.window)
        if path.scans and (not scans or path.scans[-1].odom != scans[-1].odom):
            # the newest scan too (a turn on the spot adds no travel, so no scan along the path)
            s = path.scans[-1]
            scans = [*scans, ScanSample(s.odom, s.angles[::2], s.ranges[::2], s.range_max)]
        if not scans or not self.maps():
            return Registration((), False, "no scans" if not scans else "no map", 0), None
        ends = BeamEnds.of(scans)
        return register(ends, self.maps(), self.params, self.tolerance), ends.last


def registered_hypothesis(storey: str, transform: Pose2D, odom: Pose2D) -> Hypothesis:
    """A unique registration as the hypothesis a claim is made of (no feature matched)."""
    pose = transform * odom
    return Hypothesis(
        rank=1,
        storey=storey,
        assignment=(),
        matches=[],
        n_outliers=0,
        cost=0.0,
        pose=pose,
        rectified_pose=None,
        transform=transform,
        confidence=1.0,
        support=1,
    )
