"""From confirmed features to pose hypotheses and a verdict (§3.3.2, §3.3.5).

- :mod:`~initcli.core.hypotheses.pattern` -- pair distance (Eq. 5), direction and rotation (Eq. 6, 8);
- :mod:`~initcli.core.hypotheses.matching` -- Algorithm 1 (Eq. 4-9), indexed, with outlier tolerance;
- :mod:`~initcli.core.hypotheses.cost` -- the matching cost J (Eq. 14);
- :mod:`~initcli.core.hypotheses.pose` -- trilateration (Eq. 10), heading (Eq. 11-13), rigid Kabsch;
- :mod:`~initcli.core.hypotheses.ranking` -- ranking, pose-distinct counting, confidence and verdict;
- :mod:`~initcli.core.hypotheses.rectify` -- BIM-based rectification (Eq. 17).
"""
