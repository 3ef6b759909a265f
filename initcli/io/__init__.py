"""File formats read and written by initcli (the detection log)."""
