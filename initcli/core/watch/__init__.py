"""Is a tracking localiser's pose still right? (beyond the paper: its §1 names re-initialisation
as why the system exists.)

- :mod:`~initcli.core.watch.params` -- the ``watch:`` settings of the test;
- :mod:`~initcli.core.watch.pose_check` -- the recent scans' evidence on one pose: their fit to
  the walls and the beams they send through walls;
- :mod:`~initcli.core.watch.lost_test` -- a sequential test over the distance travelled that
  decides when that evidence says the pose is wrong.
"""
