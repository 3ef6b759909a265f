"""A sequential test over the distance travelled: has the localiser's pose gone wrong?

Each check of the pose (:mod:`initcli.core.watch.pose_check`) gives a fit ``f`` (share of the
recent scans' beam ends on mapped walls) and a through-share ``s`` (share of beams that pass
through a mapped wall into the open). Its evidence of a wrong pose is

    w = s (1 - f) + a max(0, f_0 - f) + u max(0, k f_u - f) + b o        (beyond the paper)

beams through walls, which no clutter explains, discounted where the walls fit well (glass, an
open door), plus a little for a fit below ``f_0``, plus a fall below a share ``k`` of the usual fit
``f_u`` (what this robot's scans fit this map while the pose was right; only where that is at
least ``usual_min``: a map that draws what the lidar sees fits a right pose far better than a
wrong one, a walls-only one does not), plus the share ``o`` of the
robot's recent places that the pose puts inside a wall or off the building (where no robot
stands). Page's CUSUM accumulates it over travel:

    g_k = max(0, g_{k-1} + d_k (w_k - c)),   suspect when g_k > h

with ``d_k`` the metres since the previous check (at most ``max_step``): a robot standing still
adds nothing, one bad scan never decides, and a right pose (whose evidence stays below the
allowance ``c``) keeps ``g`` near 0. The travel where ``g`` last left 0 estimates where the pose
went wrong: the scans since then are the ones to re-localise with.
"""

from __future__ import annotations

from dataclasses import dataclass

from initcli.core.watch.params import WatchParams

__all__ = ["CusumTest", "wrongness"]


def wrongness(
    fit: float, through: float, off_free: float, params: WatchParams, usual: float | None = None
) -> float:
    """One check's evidence of a wrong pose, ``w`` of the module docstring (``usual``: the usual
    fit ``f_u``; None: not known yet)."""
    shortfall = params.fit_weight * max(0.0, params.fit_floor - fit)
    if usual is not None and usual >= params.usual_min:
        shortfall += params.usual_weight * max(0.0, params.usual_share * usual - fit)
    return through * (1.0 - fit) + shortfall + params.off_free_weight * off_free


@dataclass
class CusumTest:
    """Page's CUSUM over travel (module docstring); ``since`` is the travel where ``g`` last left 0."""

    params: WatchParams
    statistic: float = 0.0
    since: float = 0.0
    _last: float | None = None

    def update(self, travel: float, evidence: float) -> bool:
        """Add one check at ``travel`` m; True when the statistic passes the threshold."""
        step = 0.0 if self._last is None else min(max(travel - self._last, 0.0), self.params.max_step)
        self._last = travel
        before = self.statistic
        self.statistic = max(0.0, before + step * (evidence - self.params.allowance))
        if before == 0.0 and self.statistic == 0.0:
            self.since = travel
        elif before == 0.0:
            self.since = travel - step  # the change began after the previous check
        return self.statistic > self.params.threshold

    def reset(self, travel: float) -> None:
        self.statistic, self.since, self._last = 0.0, travel, travel
