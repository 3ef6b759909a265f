"""Driving without a pose, and with one (§3.3.3-3.3.4).

- :mod:`~initcli.core.navigation.wall_following` -- wall following on a laser scan;
- :mod:`~initcli.core.navigation.bug_navigation` -- to a target with the modified bug algorithm;
- :mod:`~initcli.core.navigation.feature_walls` -- which wall to head for on an open floor;
- :mod:`~initcli.core.navigation.frontier` -- frontier exploration on a local grid from the lidar;
- :mod:`~initcli.core.navigation.grid_planner` -- shortest paths on the BIM occupancy grid;
- :mod:`~initcli.core.navigation.confinement` -- a recent path long but small: looping or shuttling;
- :mod:`~initcli.core.navigation.laps` -- once round the space the robot is in.
"""
