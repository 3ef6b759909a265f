"""The typer app: ``--help`` lists only the registered commands."""

from __future__ import annotations

from typer.testing import CliRunner

from initcli.cli.main import app

runner = CliRunner()


def invoke(*args: str):
    return runner.invoke(app, [str(a) for a in args])


def test_help_lists_only_registered_commands() -> None:
    result = invoke("--help")
    assert result.exit_code == 0
    assert "match" in result.stdout
    commands = result.stdout.split("Commands:")[1]
    names = [line.split()[0] for line in commands.splitlines() if line.startswith("  ") and line[2:3].strip()]
    registered = [c.name or c.callback.__name__ for c in app.registered_commands]
    registered += [g.name for g in app.registered_groups]
    assert "match" in names and sorted(names) == sorted(registered)  # only what exists
    sub = invoke("match", "--help")
    for flag in (
        "--site",
        "--storey",
        "--alpha",
        "--beta",
        "--top",
        "--json",
        "--plot",
        "--max-outliers",
        "--pose-method",
        "--skip-bad",
    ):
        assert flag in sub.stdout


def test_usage_errors_are_one_line_and_exit_2(tmp_path) -> None:
    """Click's own parse errors (a word for a number, an unknown option) read like every other bad
    input: one line on stderr, exit 2, no usage block."""
    import subprocess
    import sys

    for args in (
        ["run", "--config", "x.yaml", "--seed", "abc"],
        ["match", "--nope"],
        ["eval", "--starts", "x"],
    ):
        done = subprocess.run(
            [sys.executable, "-m", "initcli.cli.main", *args], capture_output=True, text=True, cwd=tmp_path
        )
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2, done.stderr
        assert len(lines) == 1 and lines[0].startswith("bim-init: error"), done.stderr
        assert "Traceback" not in done.stderr
