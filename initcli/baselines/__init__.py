"""Baseline initialisation methods the paper compares against (§4.3): markers
(:mod:`~initcli.baselines.markers`) and AMCL (:mod:`~initcli.baselines.amcl`), both exploring at random
like every method (:mod:`~initcli.baselines.drive`) and reporting one kind of outcome
(:mod:`~initcli.baselines.outcome`)."""
