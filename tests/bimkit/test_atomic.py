"""Atomic outputs: a failed write leaves neither half a file nor half a folder behind."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bimkit.atomic import staged_directory, write_bytes_atomic, write_text_atomic


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


def test_staged_directory_replaces_the_folder_whole(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "stale.txt").write_text("from an older run")
    (target / "replaced.txt").write_text("old")
    with staged_directory(target) as stage:
        assert stage.parent == tmp_path and stage != target
        (stage / "replaced.txt").write_text("new")
        (stage / "sub").mkdir()
        (stage / "sub" / "fresh.txt").write_text("fresh")
    assert sorted(p.name for p in target.iterdir()) == ["replaced.txt", "sub"]
    assert (target / "replaced.txt").read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["site"]  # the stage and the old folder are gone


def test_staged_directory_removes_the_stage_on_ctrl_c(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "a.txt").write_text("a")
    with pytest.raises(KeyboardInterrupt), staged_directory(target) as stage:
        (stage / "a.txt").write_text("half")
        raise KeyboardInterrupt
    assert (target / "a.txt").read_text() == "a"
    assert [p.name for p in tmp_path.iterdir()] == ["site"]


@pytest.mark.parametrize("existing", [False, True])
def test_staged_directory_cleans_up_when_the_final_rename_fails(tmp_path, monkeypatch, existing):
    target = tmp_path / "site"
    if existing:
        target.mkdir()
        (target / "a.txt").write_text("a")
    real = os.replace

    def failing(src, dst):  # the staged folder cannot be put in place (the old one can go back)
        if Path(src).name.startswith(".site.") and ".old." not in Path(src).name and Path(dst) == target:
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(OSError), staged_directory(target) as stage:
        (stage / "a.txt").write_text("new")
    assert [p.name for p in tmp_path.iterdir()] == (["site"] if existing else [])
    if existing:
        assert (target / "a.txt").read_text() == "a"


def test_staged_directory_leaves_the_target_untouched_on_error(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "a.txt").write_text("a")
    with pytest.raises(RuntimeError), staged_directory(target) as stage:
        (stage / "a.txt").write_text("half")
        raise RuntimeError("boom")
    assert (target / "a.txt").read_text() == "a"
    assert [p.name for p in tmp_path.iterdir()] == ["site"]
