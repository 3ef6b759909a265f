"""The recent scans' evidence on one pose of the robot (beyond the paper): how well their beam
ends fit the map's walls there, forgiving the localiser's own small error, and what share of the
beams pass through a mapped wall into the open (which furniture, people and clutter never do), and
what share of the places the robot scanned from are not free space on the map."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bimtools.site.records import FREE, OccupancyGrid
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.registration import wall_crossings
from initcli.core.lidar.scan_fit import BeamEnds, best_scan_alignment

__all__ = ["PoseEvidence", "THROUGH_CLEAR", "THROUGH_SHORT", "off_free", "pose_evidence"]

THROUGH_SHORT = 0.3  # m: a beam must pass the wall this far before its end ...
THROUGH_CLEAR = 0.3  # m: ... and get this clear of any wall (registration's see-through test)
THROUGH_BEAMS = 600  # beams the through-wall share is measured on at most (evenly picked)


@dataclass(frozen=True)
class PoseEvidence:
    fit: float  # share of beam ends within the tolerance of a mapped wall, at the best alignment
    through: float  # share of beams through a mapped wall into the open, there
    transform: Pose2D  # odom -> map of that best alignment
    off_free: float = 0.0  # share of the scans' places (the robot's path) off the map's free cells


def pose_evidence(
    ends: BeamEnds,
    transform: Pose2D,
    fit_field: LikelihoodField,
    through_field: LikelihoodField,
    tolerance: float,
    search_m: float,
    search_deg: float,
) -> PoseEvidence:
    """``ends`` (scans in the frame of the last one) placed by ``transform`` (odom -> map), aligned
    within ``search_m`` and ``search_deg`` on ``fit_field`` (doors shut), their beams checked on
    ``through_field`` (doors open)."""
    best = best_scan_alignment(transform, ends, fit_field, tolerance, search_m, math.radians(search_deg))
    if best is None:
        return PoseEvidence(0.0, 0.0, transform)
    fit, moved = best
    origins = ends.beam_origins() if ends.origins is not None else ends.xy * 0.0
    placed = moved * ends.last
    pick = np.linspace(0, len(ends.xy) - 1, min(len(ends.xy), THROUGH_BEAMS)).astype(np.intp)
    through = wall_crossings(
        origins[pick], ends.xy[pick], placed, through_field, THROUGH_SHORT, THROUGH_CLEAR
    )
    return PoseEvidence(float(fit), float(through), moved, off_free(ends, placed, through_field.grid))


def off_free(ends: BeamEnds, placed: Pose2D, grid: OccupancyGrid) -> float:
    """Share of the places the scans of ``ends`` were taken from, put on ``grid`` by ``placed``,
    that are not free cells: inside a wall or off the mapped building, where no robot stands."""
    where = ends.origins if ends.origins is not None else np.zeros((1, 2))
    xy = placed.apply(where)
    rows, cols = grid.world_to_cell(xy[:, 0], xy[:, 1])
    h, w = grid.cells.shape
    inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    free = np.zeros(len(xy), dtype=bool)
    free[inside] = grid.cells[rows[inside], cols[inside]] == FREE
    return float(1.0 - free.mean())
