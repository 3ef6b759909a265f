"""Renamed keys: ``sim.workers`` (people walking about, not CPU workers) is now ``sim.people``; a
site.yaml with the old name is still read, as the new one, with one warning line naming the file
and the new key; one with both is one error."""

from __future__ import annotations

import pytest
import yaml

from bimkit.errors import InputError
from initcli.config import load_config
from initcli.config.load import WARNED_ENV


def _write(path, sim: dict) -> None:
    path.write_text(yaml.safe_dump({"site": {"path": "x.ifc"}, "sim": sim}))


def test_the_old_name_is_read_with_one_warning(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.delenv(WARNED_ENV, raising=False)
    path = tmp_path / "site.yaml"
    _write(path, {"workers": 5, "clutter": 0.1})
    config = load_config(path)
    assert config.sim.people == 5 and config.sim.clutter == 0.1
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("bim-init: warning: ") and str(path) in lines[0] and "sim.people" in lines[0]
    load_config(path)  # the same file again (eval loads it per trial): no second line
    load_config(path, "construction")
    assert capsys.readouterr().err == ""


def test_the_new_name_gives_no_warning(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.delenv(WARNED_ENV, raising=False)
    path = tmp_path / "site.yaml"
    _write(path, {"people": 0})
    assert load_config(path).sim.people == 0
    assert capsys.readouterr().err == ""


def test_both_names_are_one_error(tmp_path, monkeypatch) -> None:
    monkeypatch.delenv(WARNED_ENV, raising=False)
    path = tmp_path / "site.yaml"
    _write(path, {"workers": 2, "people": 3})
    with pytest.raises(InputError) as info:
        load_config(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message
    assert "sim.workers" in message and "sim.people" in message


def test_the_old_name_is_still_checked(tmp_path, monkeypatch) -> None:
    """Read as sim.people, it is checked as sim.people (its range, its type)."""
    monkeypatch.delenv(WARNED_ENV, raising=False)
    path = tmp_path / "site.yaml"
    _write(path, {"workers": -1})
    with pytest.raises(InputError, match="sim.people"):
        load_config(path)


def test_the_cli_reads_the_old_name_and_warns_once(tmp_path, monkeypatch) -> None:
    """``bim-init run`` on a config with sim.workers: one warning line on stderr, then the session."""
    import subprocess
    import sys

    from tests.helpers import SAMPLES

    monkeypatch.delenv(WARNED_ENV, raising=False)
    doc = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    doc["site"]["path"] = str(SAMPLES / "block_a.ifc")
    doc["sim"]["workers"] = doc["sim"].pop("people")
    path = tmp_path / "site.yaml"
    path.write_text(yaml.safe_dump(doc))
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "initcli.cli.main",
            "run",
            "--config",
            str(path),
            "--quiet",
            "--start",
            "10.0,11.5,90",
            "--out",
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
    )
    warnings = [line for line in done.stderr.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "sim.people" in warnings[0] and str(path) in warnings[0], done.stderr
    assert done.returncode in (0, 3, 4), done.stderr
