"""Command faces of ``bim-init``: option parsing, progress, console tables and the plots only they draw.

Each module is one command (``run``, ``match``, ``bag2log``, ``publish-pose``, ``eval``, ``survey``,
``detector``); :mod:`initcli.cli.main` holds the typer app, :mod:`initcli.cli.progress` the progress
displays and :mod:`initcli.cli.plot_hypotheses` the ``--plot`` of ``match``. Algorithms live in
:mod:`initcli.core`, file formats in :mod:`initcli.io`.
"""

__all__ = ["PROG"]

PROG = "bim-init"  # the program name of every error line (``bim-init: error: ...``)
