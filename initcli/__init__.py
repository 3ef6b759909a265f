"""initcli: the robot-side pipeline of bim-init (paper §3.3).

Layout (like the ``evo`` tool):

- :mod:`initcli.core` -- pure algorithms on numpy arrays, one concept per module, with the
  paper's equation numbers next to the code. Never imports typer, rich, json or file formats.
- :mod:`initcli.io` -- file formats (the detection log, JSON Lines version 1).
- :mod:`initcli.match.pipeline` -- orchestration of ``bim-init match`` (log + site -> hypotheses).
- :mod:`initcli.sim.synthetic_log` -- BIM features + a true path -> a detection log (tests, simulator).
- :mod:`initcli.tools` -- plotting.
- :mod:`initcli.cli.main` -- the thin typer app behind the ``bim-init`` console script.
"""

__version__ = "0.1.0"
