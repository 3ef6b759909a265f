"""File formats read and written by initcli: the detection log (:mod:`initcli.io.detection_log`)."""
