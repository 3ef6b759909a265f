"""File formats read and written by initcli: the detection log (:mod:`initcli.io.detection_log`) and
the result of ``bim-init match`` (:mod:`initcli.io.match_result`)."""
