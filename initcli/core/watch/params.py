"""The settings of the lost test (:mod:`initcli.core.watch.lost_test`), each written once with its
unit, range and default: the ``watch:`` section of site.yaml (the watch's own topics and driving
are :class:`initcli.config.session.WatchSection`)."""

from __future__ import annotations

from dataclasses import dataclass

from bimkit.settings import setting

__all__ = ["WatchParams"]


@dataclass
class WatchParams:
    """When the localiser's pose is checked, on what, and how much evidence makes it lost.

    The defaults were set on the real laser logs of ``../shared/real_lidar`` (docs/watch.md): the
    largest statistic a right pose reached there is under half the threshold."""

    check_every: float = setting(
        0.25, "m of travel between two checks of the localiser's pose", above=0, maximum=10
    )
    submap: float = setting(
        3.0,
        "m of the latest path whose scans are checked together at the localiser's pose",
        above=0,
        maximum=50,
    )
    search_m: float = setting(
        0.3,
        "m: the localiser's own error a check forgives (the scans are aligned within this of its pose)",
        minimum=0,
        maximum=2,
    )
    search_deg: float = setting(6.0, "degrees: ... and within this of its heading", minimum=0, maximum=45)
    fit_floor: float = setting(
        0.25,
        "share of beam ends on mapped walls below which a check counts the shortfall as evidence of a"
        " wrong pose (clutter lowers it at the right pose too, so only a little)",
        minimum=0,
        maximum=1,
    )
    fit_weight: float = setting(0.5, "weight of that shortfall", minimum=0, maximum=10)
    usual_share: float = setting(
        0.5,
        "share of the usual fit (the 10th percentile of the checks of the last usual_m m the pose was"
        " right)"
        " below which a check counts the shortfall as evidence: a fall from what this robot's scans"
        " fit this map; 0: off",
        minimum=0,
        maximum=1,
    )
    usual_weight: float = setting(1.0, "weight of that shortfall", minimum=0, maximum=10)
    usual_min: float = setting(
        0.8,
        "the usual fit at which that fall starts to count: a map that draws what the lidar sees (a"
        " walls-only model, where furniture and clutter hold half the beam ends, does not)",
        minimum=0,
        maximum=1,
    )
    usual_m: float = setting(30.0, "m of checks the usual fit is taken over", above=0, maximum=1000)
    off_free_weight: float = setting(
        0.5,
        "weight of the share of the robot's recent places that the pose puts off the map's free space"
        " (inside a wall, outside the building)",
        minimum=0,
        maximum=10,
    )
    allowance: float = setting(
        0.08,
        "evidence per check that a right pose is allowed (glass, open doors, a wall off the plan):"
        " only what exceeds it accumulates",
        minimum=0,
        maximum=1,
    )
    threshold: float = setting(
        0.8,
        "accumulated evidence (per m of travel) at which the pose is suspect and the lidar"
        " registration is asked where the robot is",
        above=0,
        maximum=100,
    )
    max_step: float = setting(
        1.0, "m: the most travel one check weighs (sparse scans do not weigh more)", above=0, maximum=10
    )
    confirm_margin: float = setting(
        0.15,
        "share of beam ends the registration's best place must fit better than the localiser's pose,"
        " on the same scans, for the pose to be lost (else the suspicion is dropped)",
        minimum=0,
        maximum=1,
    )
    confirm_m: float = setting(
        1.0,
        "m: the registration's best place must be this far from the localiser's ...",
        minimum=0,
        maximum=100,
    )
    confirm_deg: float = setting(15.0, "degrees: ... or turned this much from it", minimum=0, maximum=180)
    recover_every: float = setting(
        1.0, "m of travel between two registrations while lost", above=0, maximum=100
    )
    probe_every: float = setting(
        5.0,
        "m of travel between two registrations while the pose is right (a wrong pose in a place alike"
        " piles up little evidence; a unique place elsewhere that passes the claim checks makes it"
        " lost); 0: only when the evidence asks",
        minimum=0,
        maximum=1000,
    )
    probe_window: float = setting(
        10.0, "m of the latest path whose scans such a registration reads", above=0, maximum=200
    )
    min_scans_m: float = setting(
        2.0,
        "m of travel since the change the registration needs before it is asked (fewer scans fit anywhere)",
        minimum=0,
        maximum=100,
    )
