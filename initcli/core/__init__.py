"""Pure algorithms of the paper (§3.3.1-3.3.3, §3.3.5) on numpy arrays.

One concept per module; equation numbers of the paper are cited next to the code:

- :mod:`~initcli.core.geometry` -- Pose2D and SE(2) helpers.
- :mod:`~initcli.core.projection` -- Eq. 1-2 (pixel + depth -> odom) and their inverse.
- :mod:`~initcli.core.pattern` -- pair distance (Eq. 5), direction and rotation angle (Eq. 6, 8).
- :mod:`~initcli.core.detection_filter` -- sightings -> confirmed features S_object (Eq. 3).
- :mod:`~initcli.core.matching` -- Algorithm 1 (Eq. 4-9), indexed, with outlier tolerance.
- :mod:`~initcli.core.cost` -- the matching cost J (Eq. 14).
- :mod:`~initcli.core.pose` -- trilateration (Eq. 10), heading (Eq. 11-13), rigid Kabsch.
- :mod:`~initcli.core.rectify` -- BIM-based rectification (Eq. 17).
- :mod:`~initcli.core.hypotheses` -- ranking, pose-distinct counting, confidence and verdict.
- :mod:`~initcli.core.motion` -- the odometry motion model's (rot1, trans, rot2) decomposition.
- :mod:`~initcli.core.confinement` -- a recent path long but small: looping or shuttling.
"""
