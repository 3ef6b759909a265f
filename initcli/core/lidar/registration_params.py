"""The settings of the lidar's submap registration (:mod:`initcli.core.lidar.registration`), each written
once with its unit, range and default: the ``registration:`` section of site.yaml."""

from __future__ import annotations

from dataclasses import dataclass

from bimkit.settings import setting

__all__ = ["RegistrationParams"]


@dataclass
class RegistrationParams:
    """When the session registers its lidar submap over the BIM map, and when the result is unique."""

    enabled: bool = setting(
        True,
        "register the lidar submap of the recent path over every storey's map when no camera claim"
        " exists (beyond the paper: a pose with the camera off; false: the paper's pipeline)",
    )
    min_travel: float = setting(0.0, "m of travel before the first registration", minimum=0, maximum=1000)
    every: float = setting(5.0, "m of travel between two registrations", above=0, maximum=1000)
    window: float = setting(20.0, "m of the latest path whose scans make the submap", above=0, maximum=200)
    min_fit: float = setting(
        0.7,
        "share of the submap's beam ends within verification.scan_tolerance of a mapped wall that the"
        " best pose must reach",
        minimum=0,
        maximum=1,
    )
    margin: float = setting(
        0.15,
        "share of beam ends every distinct place must trail the best pose by (rooms or a corridor that"
        " repeat: no pose)",
        minimum=0,
        maximum=1,
    )
    distinct_m: float = setting(
        2.0, "m: a place this far from the best pose is distinct ...", minimum=0, maximum=100
    )
    distinct_deg: float = setting(20.0, "degrees: ... and so is one turned this much", minimum=0, maximum=180)
    see_through: float = setting(
        0.015,
        "share of beams a place alike (within margin) must send through mapped walls more than the best"
        " pose, which sends hardly any, to be ruled out (open doors its map has walls at); 0: off",
        minimum=0,
        maximum=1,
    )
    wall_lines: float = setting(
        1.0,
        "m: where every beam fits the map below min_fit, the submap is registered again on the beams on a"
        " straight line at least this long in their own scan (walls, as a building model draws them;"
        " furniture, people and material the map lacks are not); 0: never",
        minimum=0,
        maximum=20,
    )
