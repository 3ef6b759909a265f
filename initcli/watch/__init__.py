"""``bim-init watch``: a tracking localiser's pose checked against the model as the robot drives,
and re-initialised when it is lost (beyond the paper; its §1 names re-initialisation as why the
system exists).

- :mod:`~initcli.watch.records` -- the watch's states, checks and events;
- :mod:`~initcli.watch.scans` -- the recent scans kept for the checks and the re-initialisation;
- :mod:`~initcli.watch.monitor` -- :class:`~initcli.watch.monitor.Watcher`: odometry, scans and the
  localiser's poses in, events out (the same decisions live and on a recording);
- :mod:`~initcli.watch.replay` -- a recording (a detection log or a bag) through a watcher;
- :mod:`~initcli.watch.plot` -- the localiser's track, the checks over travel and the events;
- :mod:`~initcli.watch.live` -- beside Nav2 over rosbridge.
"""
