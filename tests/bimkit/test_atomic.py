"""Atomic outputs: a failed write leaves neither half a file nor half a folder behind."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import pytest

from bimkit.atomic import (
    RECORD,
    STAGE_PREFIX,
    claim,
    owned_files,
    staged_directory,
    write_bytes_atomic,
    write_text_atomic,
)
from bimkit.errors import InputError


def test_text_and_bytes_are_written_whole_and_replace_the_old_file(tmp_path):
    path = tmp_path / "deep" / "out.txt"
    write_text_atomic(path, "first")
    write_text_atomic(path, "second é")
    assert path.read_text(encoding="utf-8") == "second é"
    blob = tmp_path / "out.bin"
    write_bytes_atomic(blob, b"\x00\x01\x02")
    assert blob.read_bytes() == b"\x00\x01\x02"
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["deep", "out.bin", "out.txt"]  # no temp files


def test_a_failed_write_keeps_the_old_file(tmp_path):
    path = tmp_path / "out.txt"
    write_text_atomic(path, "old")
    with pytest.raises(TypeError):
        write_text_atomic(path, 42)  # type: ignore[arg-type]
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def _listing(folder: Path) -> list[str]:
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*"))


def test_staged_directory_makes_a_new_folder_whole_with_its_record(tmp_path):
    target = tmp_path / "site"
    with staged_directory(target) as stage:
        assert stage.parent == tmp_path and not target.exists()
        (stage / "a.txt").write_text("a")
        (stage / "sub").mkdir()
        (stage / "sub" / "b.txt").write_text("b")
    assert _listing(target) == [RECORD, "a.txt", "sub", "sub/b.txt"]
    assert owned_files(target) == {"a.txt", "sub/b.txt"}
    assert [p.name for p in tmp_path.iterdir()] == ["site"]
    mask = os.umask(0)
    os.umask(mask)
    assert target.stat().st_mode & 0o777 == 0o777 & ~mask  # as mkdir makes it, not mkdtemp's 0700


def test_a_rerun_replaces_what_the_tool_wrote_and_keeps_every_other_file(tmp_path):
    target = tmp_path / "site"
    with staged_directory(target) as stage:
        (stage / "replaced.txt").write_text("old")
        (stage / "stale.txt").write_text("from an older run")
        (stage / "maps").mkdir()
        (stage / "maps" / "old.pgm").write_text("old map")
    (target / "notes.txt").write_text("the user's")
    (target / "maps" / "mine.txt").write_text("the user's too")
    with staged_directory(target) as stage:
        assert stage.parent == target  # staged inside: no rename of the folder itself
        (stage / "replaced.txt").write_text("new")
        (stage / "fresh.txt").write_text("fresh")
    assert _listing(target) == [RECORD, "fresh.txt", "maps", "maps/mine.txt", "notes.txt", "replaced.txt"]
    assert (target / "replaced.txt").read_text() == "new"
    assert (target / "notes.txt").read_text() == "the user's"
    assert owned_files(target) == {"fresh.txt", "replaced.txt"}


def test_a_new_file_landing_on_a_file_the_tool_did_not_write_is_refused(tmp_path):
    target = tmp_path / "mine"
    target.mkdir()
    (target / "features.csv").write_text("the user's own table")
    with pytest.raises(
        InputError, match=r"features.csv: would be replaced, but was not written by this tool"
    ):
        with staged_directory(target) as stage:
            (stage / "features.csv").write_text("new")
    assert _listing(target) == ["features.csv"]
    assert (target / "features.csv").read_text() == "the user's own table"


def test_a_folder_from_before_the_record_counts_as_the_tools_where_its_marker_is(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "site.json").write_text("{}")
    (target / "features.csv").write_text("old")
    (target / "notes.txt").write_text("kept")
    with staged_directory(target, ("site.json",)) as stage:
        (stage / "site.json").write_text('{"new": 1}')
        (stage / "features.csv").write_text("new")
    assert (target / "features.csv").read_text() == "new"
    assert (target / "notes.txt").read_text() == "kept"
    assert owned_files(target) == {"features.csv", "site.json"}


def test_claim_adds_what_a_tool_wrote_bit_by_bit(tmp_path):
    (tmp_path / "results.jsonl").write_text("{}")
    (tmp_path / ".sites").mkdir()
    (tmp_path / ".sites" / "a.csv").write_text("x")
    (tmp_path / "notes.txt").write_text("the user's")
    claim(tmp_path, ("results.jsonl", ".sites", "fig*.png"))
    assert owned_files(tmp_path) == {"results.jsonl", ".sites/a.csv"}


def test_a_record_cannot_make_the_tool_remove_files_outside_its_folder(tmp_path):
    outside = tmp_path / "precious.txt"
    outside.write_text("keep me")
    target = tmp_path / "out"
    target.mkdir()
    (target / RECORD).write_text(json.dumps({"files": ["../precious.txt", str(outside), "x.txt"]}))
    (target / "x.txt").write_text("old")
    with staged_directory(target) as stage:
        (stage / "x.txt").write_text("new")
    assert outside.read_text() == "keep me"
    assert (target / "x.txt").read_text() == "new"


def test_staged_directory_removes_the_stage_on_ctrl_c(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "a.txt").write_text("a")
    with pytest.raises(KeyboardInterrupt), staged_directory(target) as stage:
        (stage / "a.txt").write_text("half")
        raise KeyboardInterrupt
    assert (target / "a.txt").read_text() == "a"
    assert [p.name for p in tmp_path.iterdir()] == ["site"]
    assert _listing(target) == ["a.txt"]


@pytest.mark.parametrize("existing", [False, True])
def test_staged_directory_restores_everything_when_a_move_fails(tmp_path, monkeypatch, existing):
    target = tmp_path / "site"
    if existing:
        with staged_directory(target) as stage:
            (stage / "a.txt").write_text("a")
            (stage / "b.txt").write_text("b")
    real = os.replace
    calls = []

    def failing(src, dst):  # the second new file cannot be put in place
        if Path(src).name == "b.txt" and STAGE_PREFIX in str(src):
            raise OSError(28, "No space left on device")
        calls.append((src, dst))
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(OSError), staged_directory(target) as stage:
        (stage / "a.txt").write_text("new a")
        (stage / "b.txt").write_text("new b")
        if not existing:
            raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "replace", real)
    if existing:
        assert _listing(target) == [RECORD, "a.txt", "b.txt"]
        assert (target / "a.txt").read_text() == "a" and (target / "b.txt").read_text() == "b"
    else:
        assert not target.exists()
    assert [p.name for p in tmp_path.iterdir()] == (["site"] if existing else [])


def test_staged_directory_leaves_the_target_untouched_on_error(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "a.txt").write_text("a")
    with pytest.raises(RuntimeError), staged_directory(target) as stage:
        (stage / "a.txt").write_text("half")
        raise RuntimeError("boom")
    assert (target / "a.txt").read_text() == "a"
    assert [p.name for p in tmp_path.iterdir()] == ["site"]
    assert _listing(target) == ["a.txt"]


def test_ctrl_c_in_the_middle_of_a_replacement_waits_for_its_end(tmp_path, monkeypatch):
    # Ctrl-C as Python has it, whatever handler an earlier import or test left in this process
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    target = tmp_path / "site"
    with staged_directory(target) as stage:
        for name in ("a.txt", "b.txt"):
            (stage / name).write_text("old")
    real = os.replace
    sent = []

    def interrupted(src, dst):
        if not sent:  # Ctrl-C between the moves of one replacement
            sent.append(True)
            os.kill(os.getpid(), signal.SIGINT)
        return real(src, dst)

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt), staged_directory(target) as stage:
        for name in ("a.txt", "b.txt"):
            (stage / name).write_text("new")
    monkeypatch.setattr(os, "replace", real)
    signal.signal(signal.SIGINT, previous)
    assert sent
    assert [(target / n).read_text() for n in ("a.txt", "b.txt")] == ["new", "new"]  # whole, not half
    assert _listing(target) == [RECORD, "a.txt", "b.txt"]
