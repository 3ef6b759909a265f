"""results.jsonl: one line per trial, read back whole, an interrupted last line dropped, bad lines named."""

from __future__ import annotations

import pytest

from bimkit.errors import InputError
from initcli.eval.records import TrialRecord
from initcli.eval.results_file import (
    ResultsWriter,
    read_results,
    record_line,
    truncate_partial_line,
    write_csv,
)


def trial(start: int, success: bool = True) -> TrialRecord:
    return TrialRecord(
        site="block_a",
        start=start,
        method="bim",
        success=success,
        reason="initialised" if success else "gave up",
        features=4,
        distance_m=12.5,
        error_translation_m=0.2 if success else None,
        error_rotation_deg=1.5 if success else None,
        confident_wrong=False,
        seconds=3.0,
    )


def test_writer_and_reader_round_trip_and_resume(tmp_path) -> None:
    path = tmp_path / "out" / "results.jsonl"
    with ResultsWriter(path, append=False) as writer:
        writer.write(trial(0))
        writer.write(trial(1, success=False))
    assert read_results(path) == [trial(0), trial(1, success=False)]
    path.write_text(path.read_text() + record_line(trial(2))[:20])  # interrupted mid-line
    assert read_results(path) == [trial(0), trial(1, success=False)]
    with ResultsWriter(path, append=True) as writer:  # resuming cuts the partial line first
        writer.write(trial(2))
    assert [r.start for r in read_results(path)] == [0, 1, 2]


def test_truncate_partial_line(tmp_path) -> None:
    path = tmp_path / "r.jsonl"
    path.write_bytes(b'{"a":1}\n{"b":')
    truncate_partial_line(path)
    assert path.read_bytes() == b'{"a":1}\n'
    truncate_partial_line(path)
    assert path.read_bytes() == b'{"a":1}\n'


def test_bad_lines_are_named(tmp_path) -> None:
    path = tmp_path / "r.jsonl"
    path.write_text(record_line(trial(0)) + "\n{oops\n" + record_line(trial(1)) + "\n")
    with pytest.raises(InputError, match=r"r\.jsonl:2: invalid JSON"):
        read_results(path)
    path.write_text('{"site": "a", "start": 0, "method": "bim", "success": true}\n')
    with pytest.raises(InputError, match=r"r\.jsonl:1: missing 'reason'"):
        read_results(path)
    path.write_text("[1, 2]\n")
    with pytest.raises(InputError, match="expected a JSON object"):
        read_results(path)
    with pytest.raises(InputError, match="cannot read results"):
        read_results(tmp_path / "absent.jsonl")


def test_write_csv(tmp_path) -> None:
    path = tmp_path / "table.csv"
    write_csv(path, ["a", "b"], [{"a": 1, "b": "x,y"}, {"a": 2, "b": None}])
    assert path.read_text() == 'a,b\n1,"x,y"\n2,\n'


def test_a_trial_written_twice_is_named_by_its_lines(tmp_path) -> None:
    """The same trial (site, start, method, sweep, seed) twice would count twice in every table;
    the same start of another seed (two campaigns appended) is another trial."""
    from dataclasses import replace

    path = tmp_path / "r.jsonl"
    lines = [record_line(trial(0)), record_line(trial(1)), record_line(replace(trial(0), seed=2))]
    path.write_text("\n".join(lines) + "\n")
    assert [(r.start, r.seed) for r in read_results(path)] == [(0, 0), (1, 0), (0, 2)]
    path.write_text("\n".join([*lines, record_line(trial(1, success=False))]) + "\n")
    with pytest.raises(
        InputError, match=r"r\.jsonl:4: the trial of site 'block_a', start 1, .* is already on line 2"
    ):
        read_results(path)
