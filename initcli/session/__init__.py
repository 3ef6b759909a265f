"""``bim-init run``: a whole initialisation session (§3.3.3-3.3.5) on a robot driver.

One module per job:

- :mod:`~initcli.session.runner` -- the state machine of §3.3.4 (explore, match, active, recovery,
  coarse, fine, done) that drives the robot;
- :mod:`~initcli.session.states` -- its states and their transitions, kept in the result and the log;
- :mod:`~initcli.session.assembly` -- its collaborators, built from the session config in one place;
- :mod:`~initcli.session.perception` -- the detection log it writes, the sightings (Eq. 1-2) and
  confirmed features (Eq. 3), and the match step (Algorithm 1) on the log so far;
- :mod:`~initcli.session.claims` -- the checks a unique match passes before it is claimed (its
  rivals, negative evidence, the lidar), and the final pose's;
- :mod:`~initcli.session.escapes` -- out of loops and shuttling, and across open floors;
- :mod:`~initcli.session.looks` -- turning in place: the initial look, looks on open floors, the
  recovery rotation;
- :mod:`~initcli.session.exploration` -- active exploration toward the features that tell the
  hypotheses apart (Eq. 15-16);
- :mod:`~initcli.session.fine_tuning` -- the particle filter seeded at the rectified pose (Eq. 18);
- :mod:`~initcli.session.result` -- what a session found, and its errors against truth;
- :mod:`~initcli.session.simulated` -- a session on the simulated robot (:mod:`initcli.sim.build`):
  assembled from its config and run into an output folder;
- :mod:`~initcli.session.live` -- a session on a live robot over rosbridge, its pose sent to Nav2;
- :mod:`~initcli.session.outputs` -- ``summary.json`` and ``report.png``.
"""
