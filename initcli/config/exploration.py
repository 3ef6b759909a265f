"""The ``exploration:`` section of the session config: wall following, the session's escapes
(loops, shuttling, frontiers, laps round a closed room) and active exploration's targets, each
setting written once with its unit, range and default (:mod:`bimkit.settings`)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from bimkit.settings import section, setting
from initcli.config.matching import D_THRE

__all__ = [
    "ExplorationSection",
    "FrontierSettings",
    "LapSettings",
    "LoopSettings",
    "ShuttleSettings",
    "TargetSettings",
    "WallSide",
]


class WallSide(StrEnum):
    """The wall random exploration follows (``exploration.wall_side``)."""

    LEFT = "left"
    RIGHT = "right"


@dataclass
class LoopSettings:
    """A loop: driving a long way in a short time without leaving a small area (circling an island of
    clutter, a chicane, an open hall with no wall in reach)."""

    window: float = setting(45.0, "s of path checked for a loop", above=0, maximum=3600)
    length: float = setting(
        8.0,
        "m driven in that window (a robot arcing at 0.3 m/s on a 0.7 m radius drives 12 m) ...",
        minimum=0,
        maximum=10000,
    )
    radius: float = setting(
        2.5, "m: ... staying this close to the path's centre is a loop", above=0, maximum=1000
    )
    escape: float = setting(
        25.0,
        "s driving out of a loop (or shuttling) toward an unexplored opening or open space",
        above=0,
        maximum=3600,
    )
    open_reach: float = setting(
        8.0,
        "m along the longest free beam to the point a loop escape heads for when no opening is known ...",
        above=0,
        maximum=1000,
    )
    open_short: float = setting(
        1.0, "m: ... or this much short of what that beam hit", minimum=0, maximum=1000
    )
    blind_reach: float = setting(
        2.0,
        "m straight ahead a loop escape heads for when there is no scan to pick a beam from",
        above=0,
        maximum=1000,
    )


@dataclass
class ShuttleSettings:
    """Shuttling: back and forth over the same few metres for minutes (a dead end behind a material
    stack the followed wall leads around, targets that keep failing): follow the other wall."""

    window: float = setting(150.0, "s of path checked for shuttling", above=0, maximum=36000)
    length: float = setting(
        30.0, "m driven in that window (0.2 m/s on average with the defaults) ...", minimum=0, maximum=100000
    )
    radius: float = setting(
        8.0, "m: ... without leaving a circle this size is shuttling", above=0, maximum=10000
    )


@dataclass
class FrontierSettings:
    """The local map of what the lidar has seen, whose unexplored openings loop escapes head for."""

    scan_every: int = setting(
        10,
        "control periods between the scans written into it (1 Hz at the 10 Hz control rate) ...",
        minimum=1,
        maximum=1000,
    )
    beam_step: int = setting(2, "... each beam_step-th beam of them", minimum=1, maximum=1000)


@dataclass
class LapSettings:
    """A lap: back where the robot was after its path turned once round (a room, a hall, a corridor
    section closed at both ends) with no new feature on the way: it heads for an opening of its
    local map it can pass, and with none left it is shut in (beyond the paper)."""

    length: float = setting(6.0, "m: a lap is at least this long ...", above=0, maximum=10000)
    radius: float = setting(1.0, "m: ... back this close to where it began ...", above=0, maximum=100)
    turn: float = setting(
        315.0, "degrees: ... the path's direction turned by at least this much", above=0, maximum=3600
    )
    shut_in: bool = setting(
        True,
        "stop the session when a lap brought no new feature and the local map has no opening the robot can"
        " pass (reason: shut in, with the area explored, the features seen and what to do); false: drive"
        " on to limits.max_distance",
    )


@dataclass
class TargetSettings:
    """Active exploration's targets (paper 3.3.4, exploration.active)."""

    hypotheses: int = setting(
        5,
        "hypotheses (most probable first) whose targets active exploration validates",
        minimum=1,
        maximum=1000,
    )
    view_distance: float = setting(
        1.8,
        "m in front of a target feature where active exploration goes to look at it",
        minimum=0,
        maximum=100,
    )
    discrimination_radius: float = setting(
        1.5,
        "m: another hypothesis predicting a same-category feature this close to a target agrees with it (the"
        " target tells them not apart)",
        minimum=0,
        maximum=100,
    )
    visited_radius: float = setting(
        2.0, "m: a target this close to one visited before is skipped", minimum=0, maximum=100
    )
    planner_margin: float = setting(
        0.1, "m of clearance added to robot.radius when planning routes", minimum=0, maximum=10
    )
    travel_slack: float = setting(
        1.5,
        "the time allowed to get to a target: the route's length over robot.max_linear, times this ...",
        minimum=0,
        maximum=100,
    )
    travel_cap: float = setting(
        120.0, "s: ... at most this, on top of exploration.t_thre", minimum=0, maximum=36000
    )
    stall: float = setting(
        15.0,
        "s without getting closer to the route's next waypoint: the route is blocked",
        above=0,
        maximum=3600,
    )
    progress_step: float = setting(
        0.5, "m closer to the waypoint that counts as progress", minimum=0, maximum=100
    )
    waypoint_cost: float = setting(
        2.0, "m added to the remaining distance for each waypoint still ahead", minimum=0, maximum=100
    )
    look: float = setting(2.0, "s spent at a reached target looking for its feature", minimum=0, maximum=3600)
    max_fruitless: int = setting(
        3,
        "targets in a row without a new feature after which random exploration takes over",
        minimum=1,
        maximum=1000,
    )


@dataclass
class ExplorationSection:
    wall_side: str = setting(
        WallSide.LEFT.value, "the wall random exploration follows", enum=tuple(s.value for s in WallSide)
    )
    wall_distance: float = setting(0.7, "m kept to the followed wall", above=0, maximum=10)
    front_clearance: float = setting(
        0.2,
        "m beyond robot.radius: an obstacle this close ahead stops the wall follower, which turns in place"
        " away from the wall",
        minimum=0,
        maximum=10,
    )
    d_thre: float = D_THRE()
    t_thre: float = setting(
        25.0, "s without a new feature during active exploration -> recovery", above=0, maximum=3600
    )
    active: bool = setting(
        False,
        "BIM-based active exploration (paper 3.3.4) with several but fewer than matching.m_thre hypotheses,"
        " and toward a claim's credible rivals; false: wall following until one hypothesis is left (in the"
        " site as built wall following initialised more sessions)",
    )
    max_route: float = setting(
        0.0,
        "m: active exploration takes no target farther along the corridors than this; 0: any",
        minimum=0,
        maximum=10000,
    )
    recovery: bool = setting(
        True,
        "active exploration that finds nothing within t_thre turns in place to widen the view (paper 3.3.4);"
        " false: on to the next target",
    )
    initial_look: bool = setting(
        True, "turn once on the spot before exploring: features behind the robot cost no distance"
    )
    look_every: float = setting(
        10.0,
        "m of travel without a new feature while following a wall with open space (3 m or more) on the"
        " other side -> turn once on the spot again; 0: never",
        minimum=0,
        maximum=1000,
    )
    cross_after: int = setting(
        6,
        "looks on an open floor (look_every) since the last new feature after which the robot drives across"
        " the floor on the open side (to a wall 2 m wide or more that the lidar sees up to 16.5 m away,"
        " along a way 1.6 m wide, stopping 1.5 m short) and follows the wall found there; 0: never",
        minimum=0,
        maximum=1000,
    )
    long_walls: bool = setting(
        True,
        "out of a short lap round a column on an open floor (12 m or less, enclosing under a fifth of the"
        " area mapped) to the nearest long wall (4 m or more) the lidar sees that the path has not followed,"
        " where the doors and stairs are; false: to an opening of the local map, as after any lap",
    )
    feature_walls: bool = setting(
        True,
        "after a look on an open floor that found nothing new, with targets.hypotheses or fewer hypotheses,"
        " drive across to the wall the lidar sees where most of them put a feature not yet seen; false:"
        " only the crossings of cross_after",
    )
    turn: float = setting(
        360.0,
        "degrees turned in place by a look (the initial one, one on an open floor) and by the recovery"
        " rotation",
        above=0,
        maximum=3600,
    )
    turn_rate: float = setting(
        0.6, "share of robot.max_angular the robot turns in place at (looks, recovery)", above=0, maximum=1
    )
    loops: LoopSettings = section(LoopSettings, "driving out of a loop (beyond the paper)")
    shuttles: ShuttleSettings = section(
        ShuttleSettings, "following the other wall when shuttling (beyond the paper)"
    )
    frontier: FrontierSettings = section(
        FrontierSettings, "the local map of unexplored openings that loop escapes head for"
    )
    laps: LapSettings = section(LapSettings, "laps round a room or hall without a new feature: shut in?")
    targets: TargetSettings = section(TargetSettings, "active exploration's targets (exploration.active)")
