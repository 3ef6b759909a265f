"""Pure algorithms of the paper (§3.3.1-3.3.5) on numpy arrays, one subpackage per concern, in the
order the data flows: no file formats, no command-line or console libraries.

- :mod:`~initcli.core.geometry` -- poses, the odometry motion, the camera's projection (Eq. 1-2),
  rays against walls;
- :mod:`~initcli.core.features` -- detector classes, sightings -> confirmed features (Eq. 3), which
  features a camera sees;
- :mod:`~initcli.core.hypotheses` -- Algorithm 1 (Eq. 4-9), the cost (Eq. 14), the pose (Eq. 10-13),
  ranking and the verdict, rectification (Eq. 17);
- :mod:`~initcli.core.lidar` -- lines, landmarks and the fit of a scan, the submap registration,
  self-similar storeys and lidar twins;
- :mod:`~initcli.core.verify` -- a hypothesis checked against evidence Algorithm 1 does not use;
- :mod:`~initcli.core.filters` -- particle filters: fine tuning (Eq. 18) and AMCL global localisation;
- :mod:`~initcli.core.navigation` -- wall following, the bug algorithm, frontiers, grid paths, loops.
"""
