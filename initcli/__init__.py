"""initcli: the robot-side pipeline of bim-init (paper §3.3), the ``bim-init`` command.

Layout (like the ``evo`` tool):

- :mod:`initcli.core` -- pure algorithms on numpy arrays, one concept per module, with the
  paper's equation numbers next to the code. Never imports typer, rich, json or file formats.
- :mod:`initcli.io` -- file formats (the detection log, JSON Lines version 1; the match result).
- :mod:`initcli.match` -- ``bim-init match``: a detection log and a site model -> hypotheses.
- :mod:`initcli.session` -- ``bim-init run``: a whole initialisation session on a robot driver.
- :mod:`initcli.drivers` -- the robot driver interface (the simulated robot is :mod:`initcli.sim.driver`,
  the live one :mod:`initcli.ros.rosbridge_driver`).
- :mod:`initcli.sim` -- the simulated world, robot, camera and synthetic logs built from the BIM.
- :mod:`initcli.detector` -- the object detector: ONNX runtime, synthetic data, training.
- :mod:`initcli.ros` -- ROS bags in and out, Nav2 messages and the rosbridge link, without ROS.
- :mod:`initcli.baselines` -- the methods the paper compares against (markers, AMCL).
- :mod:`initcli.eval` -- ``bim-init eval``: the paper's Tables 2 and 3.
- :mod:`initcli.survey` -- ``bim-init survey``: where on a floor a robot can initialise.
- :mod:`initcli.config` (the session config), :mod:`initcli.config.building` (the site model a config names),
  :mod:`initcli.executor` (process pool or Ray cluster).
- :mod:`initcli.cli` -- the thin command faces; :mod:`initcli.cli.main` is the typer app behind the
  ``bim-init`` console script.
"""

__version__ = "0.1.0"
