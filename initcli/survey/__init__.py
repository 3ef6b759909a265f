"""``bim-init survey``: where on a floor a robot can initialise, from the BIM alone.

:mod:`~initcli.survey.exploration` (the deterministic exploration path: a turn on the spot, then wall
following along the wall-distance contour of the circulation area), :mod:`~initcli.survey.uniqueness`
(incremental Algorithm 1 until one hypothesis is left), :mod:`~initcli.survey.survey` (samples,
summary, landmark suggestions) and :mod:`~initcli.survey.plots`; the camera model is the
simulator's, noise-free and batched over poses (:mod:`initcli.core.features.visibility`).
"""
