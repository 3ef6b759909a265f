"""The 2D lidar against the BIM's walls (beyond the paper).

- :mod:`~initcli.core.lidar.scan_lines` -- straight lines in one scan (split and merge);
- :mod:`~initcli.core.lidar.scan_landmarks` -- corners and openings in one scan;
- :mod:`~initcli.core.lidar.landmark_tracks` -- those landmarks confirmed along a path;
- :mod:`~initcli.core.lidar.scan_fit` -- the scans' fit of a pose to the walls, and its best correction;
- :mod:`~initcli.core.lidar.registration` -- the submap registration over a storey's map, and
  :mod:`~initcli.core.lidar.registration_params` its settings;
- :mod:`~initcli.core.lidar.symmetry` -- self-similar storeys;
- :mod:`~initcli.core.lidar.region_twins` -- spaces a lidar cannot tell apart.
"""
