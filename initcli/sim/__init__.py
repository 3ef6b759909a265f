"""The embedded robot: a differential-drive robot simulated in the storey's walls (from the BIM).

- :mod:`~initcli.sim.build` -- the simulated robot in its world, built from a session config;
- :mod:`~initcli.sim.driver` -- the simulated robot behind the driver interface (lidar, camera, odometry);
- :mod:`~initcli.sim.world` -- the world: the storey's obstacles plus clutter and walking workers;
- :mod:`~initcli.sim.as_built` -- the site as built, not as designed (doors missing, shifted, open);
- :mod:`~initcli.sim.scenario` -- random starts in the circulation area (:mod:`initcli.storey`),
  clutter and workers;
- :mod:`~initcli.sim.robot` -- true motion and wheel odometry that drifts;
- :mod:`~initcli.sim.camera` -- the simulated RGB-D camera and detector with realistic errors;
- :mod:`~initcli.sim.rendered_camera`, :mod:`~initcli.sim.onnx_camera` -- a rendered view and the
  ONNX detector in the loop instead;
- :mod:`~initcli.sim.markers` -- the ArUco tags of the marker baseline;
- :mod:`~initcli.sim.synthetic_log`, :mod:`~initcli.sim.synthetic_floor`,
  :mod:`~initcli.sim.synthetic_paths` -- synthetic detection logs, floors and paths (tests, benchmarks).
"""
