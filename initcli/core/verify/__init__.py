"""A pose hypothesis checked against evidence Algorithm 1 does not use (beyond the paper): the one
home of the checks; :mod:`initcli.verify` runs them on a log, for ``bim-init match`` and the session.

- :mod:`~initcli.core.verify.checks` -- negative evidence, the lidar's fit, rivals, the judgement;
- :mod:`~initcli.core.verify.params` -- their thresholds, each written once.
"""
