"""``bim-init eval``: the paper's Tables 2 and 3 (§4), reproduced with the baselines beside them.

:mod:`~initcli.eval.config` (``eval.yaml``), :mod:`~initcli.eval.campaign` (planning and running the
trials, resumable), :mod:`~initcli.eval.trial` (one start, every method), :mod:`~initcli.eval.sweep`
(one parameter varied), :mod:`~initcli.eval.records` and :mod:`~initcli.eval.results_file` (the
trials and ``results.jsonl``), :mod:`~initcli.eval.scoring` (§4.3), :mod:`~initcli.eval.tables` and
:mod:`~initcli.eval.paper` (Tables 2 and 3 with the paper's figures), :mod:`~initcli.eval.plots`
(Fig. 9, Fig. 12) and :mod:`~initcli.eval.report` (everything written after the trials).
"""
