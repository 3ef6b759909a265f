"""``bim-init``: the typer app that gathers every command face of :mod:`initcli.cli`.

Commands: ``match`` (:mod:`initcli.cli.match`), ``run`` (:mod:`initcli.cli.run`), ``eval``
(:mod:`initcli.cli.eval`), ``detector`` (:mod:`initcli.cli.detector`), ``bag2log``
(:mod:`initcli.cli.bag2log`), ``publish-pose`` (:mod:`initcli.cli.publish_pose`), ``survey``
(:mod:`initcli.cli.survey`), ``watch`` (:mod:`initcli.cli.watch`). Bad input exits with 2 and one
line on stderr, never a traceback.
"""

from __future__ import annotations

import typer

from bimkit.cli import HELP, run_cli
from initcli.cli import PROG
from initcli.cli.bag2log import bag2log
from initcli.cli.detector import detector_app
from initcli.cli.eval import evaluate
from initcli.cli.match import match
from initcli.cli.publish_pose import publish_pose
from initcli.cli.run import run as run_session_command
from initcli.cli.survey import survey
from initcli.cli.watch import watch

__all__ = ["app", "main"]

app = typer.Typer(
    name="bim-init",
    help="Marker-free robot initialisation from BIM: match detected doors, lifts and stairs to the model.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    **HELP,
)


@app.callback()
def _root() -> None:
    """Marker-free robot initialisation from BIM (paper §3.3): match detected doors, lifts and
    staircases to the same elements of the building model."""


app.command("match")(match)
app.command("run")(run_session_command)
app.command("eval")(evaluate)
app.command("bag2log")(bag2log)
app.command("publish-pose")(publish_pose)
app.command("survey")(survey)
app.command("watch")(watch)
app.add_typer(detector_app, name="detector")


def main() -> None:
    """Console-script entry point (``bim-init``)."""
    run_cli(app, PROG)


if __name__ == "__main__":
    main()
