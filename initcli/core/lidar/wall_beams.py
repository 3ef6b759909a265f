"""The beams of a scan that end on a wall as a building model draws one: a straight line at least
some metres long in the scan itself (beyond the paper).

A map drawn from a BIM, or a walls-only map, has walls and nothing else; a real scan also ends on
furniture, people, plants and stacks of material the map lacks. Beams on such clutter pull the
submap registration's fit down everywhere (on the four real laser logs measured, the true place's fit
fell from 0.85-1.0 to 0.3-0.6 on walls-only maps) and can fit a wrong place as well as the right one.
Keeping only the beams on the scan's long straight lines
(:func:`~initcli.core.lidar.scan_lines.extract_lines`) lays walls on walls: clutter is short,
round or ragged. Pure numpy.
"""

from __future__ import annotations

import math

import numpy as np

from initcli.core.lidar.scan_fit import ScanSample
from initcli.core.lidar.scan_lines import extract_lines

__all__ = ["wall_beams"]


def wall_beams(scan: ScanSample, min_length: float) -> ScanSample:
    """``scan`` with every beam that is not on a straight line at least ``min_length`` m long made a
    no return (its range set past ``range_max``); ``min_length`` 0 keeps every beam. The beams must
    be evenly spaced (as a LaserScan's are)."""
    if min_length <= 0 or len(scan.ranges) < 3:
        return scan
    angles = np.asarray(scan.angles, dtype=float)
    step = float(angles[1] - angles[0])
    if not math.isfinite(step) or step == 0.0:
        return scan
    keep = np.zeros(len(scan.ranges), dtype=bool)
    for line in extract_lines(scan.ranges, float(angles[0]), step, scan.range_max):
        if float(np.hypot(*(line.end - line.start))) >= min_length:
            if line.first <= line.last:
                keep[line.first : line.last + 1] = True
            else:  # a line across the start of a full turn: its beams wrap round
                keep[line.first :] = True
                keep[: line.last + 1] = True
    ranges = np.where(keep, scan.ranges, np.inf)
    return ScanSample(scan.odom, scan.angles, ranges, scan.range_max)
