"""``bim-init survey``: where on a floor a robot can initialise, from the BIM alone.

- :mod:`~initcli.survey.exploration` -- the deterministic exploration path: a turn on the spot, then
  wall following along the wall-distance contour of the circulation area;
- :mod:`~initcli.survey.uniqueness` -- incremental Algorithm 1 until one hypothesis is left;
- :mod:`~initcli.survey.plan` -- the settings and the storey precomputed: features, occluders,
  loops, the start samples;
- :mod:`~initcli.survey.spaces` -- the spaces a start fails in, doors shut: shut-in rooms, lidar twins;
- :mod:`~initcli.survey.sequences` -- per start, the features confirmed in order and the distance to each;
- :mod:`~initcli.survey.run` -- the matching on an executor: the distance to a unique match per start;
- :mod:`~initcli.survey.summary` -- the per-storey numbers of ``survey.json``;
- :mod:`~initcli.survey.landmarks` -- the greedy landmark suggestions;
- :mod:`~initcli.survey.plots` -- the maps.

The storey's geometry (circulation area, closed door leaves, outlines) is :mod:`initcli.storey`; the
camera model is the simulator's, noise-free and batched over poses (:mod:`initcli.core.features.visibility`).
"""
