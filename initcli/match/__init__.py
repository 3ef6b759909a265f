"""The matching pipeline over a detection log: sightings -> confirmed features -> hypotheses -> pose.

:func:`initcli.match.pipeline.match_log` composes the pure steps of :mod:`initcli.core` (Eq. 1-17,
Algorithm 1) on a :class:`~initcli.io.detection_log.DetectionLog` and a site model; ``bim-init
match`` and the online session both call it. By job: :mod:`initcli.match.load` reads and checks the
log and the site; :mod:`initcli.match.sightings` turns the log's images into sightings (Eq. 1-2), for
the pipeline and, image by image, for the session; :mod:`initcli.match.features` makes them
confirmed features (with :mod:`initcli.match.landmarks`, the lidar's); :mod:`initcli.match.search`
runs Algorithm 1 and ranks its matches into a :class:`~initcli.match.report.MatchReport`
(:mod:`initcli.match.report`, whose outcome the command turns into its exit code);
:mod:`initcli.verify.evidence` checks the hypotheses against the log (negative evidence, the
lidar); :mod:`initcli.match.report_file` writes the result as JSON (``match_result.schema.json``).
"""
