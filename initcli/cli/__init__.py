"""Command faces of ``bim-init``: option parsing, progress, console tables and the plots only they draw.

Each module is one command (``run``, ``match``, ``bag2log``, ``publish-pose``, ``eval``, ``survey``,
``detector``); :mod:`initcli.cli.main` holds the typer app, :mod:`initcli.cli.progress` the progress
displays and :mod:`initcli.cli.plot_hypotheses` the ``--plot`` of ``match``. Algorithms live in
:mod:`initcli.core`, file formats in :mod:`initcli.io`.
"""

from bimkit.errors import InputError
from initcli.config.sim import REALITY_PROFILES

__all__ = ["PROG", "check_reality"]

PROG = "bim-init"  # the program name of every error line (``bim-init: error: ...``)


def check_reality(reality: str | None) -> None:
    """A ``--reality`` option names a profile of ``sim.reality`` (None: not given)."""
    if reality is not None and reality not in REALITY_PROFILES:
        raise InputError(f"--reality: expected one of {', '.join(REALITY_PROFILES)}, got {reality!r}")
