"""The covariance sent with a fine-tuned pose (beyond the paper): what Eq. 18's particle cloud says,
plus what it cannot see.

A converged particle filter's spread measures how well the scans pin the pose on the map as drawn;
it knows nothing of walls built elsewhere than drawn, which move its estimate without widening the
cloud. Three additions keep the covariance honest:

    C = C_pf + d d^T + J + diag(s_xy^2, s_xy^2, s_yaw^2)

* ``d``: the fine pose less the coarse claim carried by odometry (the rectified pose of Eq. 17): two
  estimates of one pose from different evidence (features against the scans), each off by about
  their difference when they disagree;
* ``J``: how far the pose moves when a part of the last scan is left out
  (:mod:`initcli.core.lidar.scan_jackknife`): a hoarding or a wall built off its line that the
  whole cloud followed;
* a floor ``s_xy``, ``s_yaw``: how well a map of cells of a few centimetres can place anything.
"""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.se2 import Pose2D

__all__ = ["honest_covariance"]


def honest_covariance(
    particles: np.ndarray,
    estimate: Pose2D,
    claim: Pose2D,
    floor_m: float,
    floor_deg: float,
    jackknife: np.ndarray | None = None,
) -> np.ndarray:
    """``C`` of the module docstring: the 3x3 (x, y, yaw) ``particles`` covariance, the fine
    ``estimate`` and the carried ``claim``, the floor in metres and degrees, and the scan's
    ``jackknife`` (none: zero)."""
    d = np.array(
        [estimate.x - claim.x, estimate.y - claim.y, math.remainder(estimate.yaw - claim.yaw, math.tau)]
    )
    floor = np.diag([floor_m**2, floor_m**2, math.radians(floor_deg) ** 2])
    jack = np.zeros((3, 3)) if jackknife is None else np.asarray(jackknife, dtype=float)
    sent: np.ndarray = np.asarray(particles, dtype=float) + np.outer(d, d) + jack + floor
    return sent
