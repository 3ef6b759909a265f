"""Pure algorithms of the paper (§3.3.1-3.3.5) on numpy arrays.

One concept per module; equation numbers of the paper are cited next to the code:

- :mod:`~initcli.core.geometry` -- Pose2D and SE(2) helpers.
- :mod:`~initcli.core.projection` -- Eq. 1-2 (pixel + depth -> odom) and their inverse.
- :mod:`~initcli.core.depth` -- the depth D of Eq. 1: a window mean at the box centre.
- :mod:`~initcli.core.classes` -- detector class names <-> BIM feature categories.
- :mod:`~initcli.core.detection_filter` -- sightings -> confirmed features S_object (Eq. 3).
- :mod:`~initcli.core.pattern` -- pair distance (Eq. 5), direction and rotation angle (Eq. 6, 8).
- :mod:`~initcli.core.matching` -- Algorithm 1 (Eq. 4-9), indexed, with outlier tolerance.
- :mod:`~initcli.core.cost` -- the matching cost J (Eq. 14).
- :mod:`~initcli.core.hypotheses` -- ranking, pose-distinct counting, confidence and verdict.
- :mod:`~initcli.core.pose` -- trilateration (Eq. 10), heading (Eq. 11-13), rigid Kabsch.
- :mod:`~initcli.core.rectify` -- BIM-based rectification (Eq. 17).
- :mod:`~initcli.core.verification` -- a hypothesis checked against evidence Algorithm 1 does not use.
- :mod:`~initcli.core.scan_fit` -- the lidar scans' fit of a pose to the BIM walls, and its best correction.
- :mod:`~initcli.core.particle_filter` -- particle-filter fine tuning (Eq. 18) on the BIM map.
- :mod:`~initcli.core.global_localisation` -- AMCL global localisation (the ``amcl`` baseline).
- :mod:`~initcli.core.marker_pose` -- the robot pose from one ArUco tag (the marker baseline).
- :mod:`~initcli.core.motion` -- the odometry motion model's (rot1, trans, rot2) decomposition.
- :mod:`~initcli.core.wall_following` -- wall following on a laser scan (§3.3.4, §3.3.3).
- :mod:`~initcli.core.bug_navigation` -- driving to a target with the modified bug algorithm (§3.3.3).
- :mod:`~initcli.core.grid_planner` -- shortest paths on the BIM occupancy grid.
- :mod:`~initcli.core.frontier` -- frontier exploration on a local grid from the lidar.
- :mod:`~initcli.core.confinement` -- a recent path long but small: looping or shuttling.
- :mod:`~initcli.core.visibility` -- which BIM features a camera sees from many poses at once.
- :mod:`~initcli.core.raycast` -- rays against line segments (the lidar, sight lines).
- :mod:`~initcli.core.grid_cache` -- values derived from an occupancy map, built once per process.
- :mod:`~initcli.core.jit` -- compiled inner loops (numba, machine code cached on disk).
"""
