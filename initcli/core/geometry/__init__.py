"""Planar geometry shared by every other part of :mod:`initcli.core`.

- :mod:`~initcli.core.geometry.se2` -- :class:`Pose2D` and SE(2) helpers;
- :mod:`~initcli.core.geometry.motion` -- the odometry motion model's (rot1, trans, rot2) decomposition;
- :mod:`~initcli.core.geometry.projection` -- Eq. 1-2 (pixel + depth -> odom) and their inverse;
- :mod:`~initcli.core.geometry.depth` -- the depth D of Eq. 1: a window mean at the box centre;
- :mod:`~initcli.core.geometry.raycast` -- rays against line segments (the lidar, sight lines);
- :mod:`~initcli.core.geometry.nearest` -- nearest points and points within a radius (a bucket grid);
- :mod:`~initcli.core.geometry.raster` -- exact distances on a raster of map cells;
- :mod:`~initcli.core.geometry.least_squares` -- Levenberg-Marquardt for small non-linear fits;
- :mod:`~initcli.core.geometry.jit` -- compiled inner loops (numba, the ``[fast]`` extra; plain
  Python without it).
"""
