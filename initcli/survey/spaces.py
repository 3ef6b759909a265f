"""The spaces a start fails in, doors shut: rooms no feature faces (a robot there is shut in) and
spaces a lidar cannot tell from another (camera off, a start there fails bar a chance difference)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from initcli.core.lidar.region_twins import IDENTITY_M, RegionTwin, moved, region_twins
from initcli.storey.circulation import Circulation

__all__ = [
    "LidarTwin",
    "SHUT_IN_LABEL",
    "SHUT_IN_MIN_AREA",
    "ShutInRoom",
    "lidar_twin_spaces",
    "shut_in_rooms",
]

SHUT_IN_MIN_AREA = 2.0  # m²: a closed-off space at least this large where a robot can stand is marked
SHUT_IN_LABEL = "cannot initialise from here"  # what the map says over a shut-in room


@dataclass(frozen=True)
class ShutInRoom:
    """A space closed off by the doors (every leaf closed) that no feature faces: a robot that
    starts there goes round it and stops shut in (the session's ``reason: shut in``)."""

    x: float  # m: a cell of the room where a robot can stand, nearest its centroid
    y: float
    area_m2: float  # where a robot can stand (the start clearance)


@dataclass(frozen=True)
class LidarTwin:
    """A space (every door leaf closed) that a turn or shift lays on itself or on another space, walls
    on walls and floor on floor (:mod:`initcli.core.lidar.region_twins`): with the camera off a lidar
    sees a pose there and its twin alike (within the session's scan tolerance), and a start there
    initialises only by a chance difference while the doors stay shut."""

    x: float  # m: a cell of the space where a robot can stand, nearest its centroid
    y: float
    area_m2: float  # where a robot can stand (the start clearance)
    twin_x: float  # m: where the lidar sees the same as at (x, y) ...
    twin_y: float
    turn_deg: float  # ... turned this much
    start_region: bool  # part of the surveyed start region (else a shut-in room)


def _standing(circulation: Circulation, clearance: float, where: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The labels of the connected free regions with cells in ``where`` that have at least
    SHUT_IN_MIN_AREA where a robot can stand (``clearance`` m from the nearest obstacle), and the
    mask of those standing cells."""
    regions = circulation.regions
    if regions is None:
        return np.zeros(0, dtype=int), np.zeros(circulation.label.shape, dtype=bool)
    stand = (regions > 0) & where & (circulation.clearance >= clearance)
    counts = np.bincount(regions[stand], minlength=int(regions.max()) + 1)
    keep = np.flatnonzero(counts * circulation.grid.resolution**2 >= SHUT_IN_MIN_AREA)
    keep = keep[keep > 0]
    return keep, stand & np.isin(regions, keep)


def _nearest_centroid(circulation: Circulation, mask: np.ndarray) -> tuple[float, float]:
    """The centre of the cell of ``mask`` nearest its centroid (m)."""
    rows, cols = np.nonzero(mask)
    k = int(np.argmin(np.hypot(rows - rows.mean(), cols - cols.mean())))
    x, y = circulation.grid.cell_centre(rows[k : k + 1], cols[k : k + 1])
    return round(float(x[0]), 2), round(float(y[0]), 2)


def shut_in_rooms(circulation: Circulation, clearance: float) -> tuple[list[ShutInRoom], np.ndarray]:
    """The connected free regions outside the surveyed ``circulation`` (every door leaf closed; no
    feature faces them) with at least SHUT_IN_MIN_AREA where a robot can stand (``clearance`` m from
    the nearest obstacle), and the mask of their cells."""
    keep, cells = _standing(circulation, clearance, ~circulation.label)
    cell = circulation.grid.resolution**2
    rooms: list[ShutInRoom] = []
    for label in keep:
        room = cells & (circulation.regions == label)
        rooms.append(ShutInRoom(*_nearest_centroid(circulation, room), round(float(room.sum() * cell), 1)))
    return rooms, cells


def _farthest_from_fixed_point(
    circulation: Circulation, mask: np.ndarray, twin: RegionTwin
) -> tuple[float, float]:
    """The standing cell of ``mask`` that the twin's motion moves farthest (m): a point whose twin
    is another place, where the space's own centre is the centre of its turn."""
    rows, cols = np.nonzero(mask)
    x, y = circulation.grid.cell_centre(rows, cols)
    xy = np.column_stack([x, y])
    k = int(np.argmax(moved(twin.motion, xy)))
    return round(float(xy[k, 0]), 2), round(float(xy[k, 1]), 2)


def lidar_twin_spaces(
    circulation: Circulation, clearance: float, tolerance: float
) -> tuple[list[LidarTwin], np.ndarray]:
    """The spaces of the map (every door leaf closed; start region and shut-in rooms, at least
    SHUT_IN_MIN_AREA where a robot can stand) that have a lidar twin, walls alike within
    ``tolerance`` m, and the mask of their cells."""
    keep, cells = _standing(circulation, clearance, np.ones(circulation.label.shape, dtype=bool))
    regions = circulation.regions
    if regions is None or not len(keep):
        return [], cells  # no space where a robot can stand: an empty mask
    grid = circulation.grid
    twins = region_twins(regions, grid.resolution, (grid.origin[0], grid.origin[1]), keep, tolerance)
    out: list[LidarTwin] = []
    mask = np.zeros(regions.shape, dtype=bool)
    for twin in twins:
        space = cells & (regions == twin.label)
        x, y = _nearest_centroid(circulation, space)
        if moved(twin.motion, np.array([x, y]))[0] < IDENTITY_M:
            x, y = _farthest_from_fixed_point(circulation, space, twin)  # the centre of a half turn
        tx, ty = twin.motion.apply(np.array([x, y]))
        start = bool((space & circulation.label).any())
        area = round(float(space.sum() * grid.resolution**2), 1)
        turn = round(twin.turn_deg, 1) + 0.0  # round(-0.04) is -0.0
        out.append(LidarTwin(x, y, area, round(float(tx), 2), round(float(ty), 2), turn, start))
        mask |= space
    return out, mask
