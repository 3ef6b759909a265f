"""The checks of :mod:`initcli.core.verify` and the lidar registration of
:mod:`initcli.core.lidar.registration` run on a detection log: the one place ``bim-init match``, the
session and the survey call them.

- :mod:`~initcli.verify.evidence` -- a match's hypotheses against the log: negative evidence, the
  lidar's fit;
- :mod:`~initcli.verify.registration` -- the lidar submap registration over a log.
"""
