"""What one localisation attempt reports, whatever the method: the record ``bim-init eval`` scores."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.se2 import Pose2D

__all__ = ["LocalisationOutcome"]


@dataclass
class LocalisationOutcome:
    """One attempt to localise from an unknown start.

    ``localised``: the method claimed a pose (converged, decoded a marker, found a unique match);
    it says nothing about whether the pose is right: ``bim-init eval`` compares ``pose`` with
    ``truth`` (the true pose at the same instant) and applies the paper's failure rule.
    """

    method: str
    localised: bool
    reason: str
    pose: Pose2D | None  # BIM frame, at the moment the method claimed it
    truth: Pose2D | None  # true pose at that moment (or at the end when nothing was claimed)
    distance_m: float  # driven until the claim (or until giving up)
    duration_s: float  # simulated seconds
    features: int = 0  # what the method detected: BIM features, markers decoded, 0 for AMCL
    wall_seconds: float = 0.0
    # The simulator refused the start (a space closed off from the corridors, known at 0 m, or a
    # storey with no free space to draw a start from): neither a success nor a failure of the method.
    refused: bool = False
    # the 3x3 (x, y, yaw) covariance the method claims with its pose (what Nav2 is sent); None: none
    covariance: np.ndarray | None = None
