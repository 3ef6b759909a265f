"""Robot drivers: velocity commands in; odometry, laser scans and detections out.

:class:`initcli.drivers.base.RobotDriver` is the interface the session logic talks to; the
simulator's driver (:mod:`initcli.sim.driver`) is the embedded default, a real robot driver replaces it
without touching the logic.
"""
