"""Atomic outputs: a failed write leaves neither half a file nor half a folder behind."""

from __future__ import annotations

import pytest

from bimtools.site.atomic import staged_directory, write_bytes_atomic, write_text_atomic


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


def test_staged_directory_replaces_written_files_and_keeps_the_others(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "kept.txt").write_text("kept")
    (target / "replaced.txt").write_text("old")
    (target / "sub").mkdir()
    (target / "sub" / "stale.txt").write_text("stale")
    with staged_directory(target) as stage:
        assert stage.parent == tmp_path and stage != target
        (stage / "replaced.txt").write_text("new")
        (stage / "sub").mkdir()
        (stage / "sub" / "fresh.txt").write_text("fresh")
    assert (target / "kept.txt").read_text() == "kept"
    assert (target / "replaced.txt").read_text() == "new"
    assert [p.name for p in (target / "sub").iterdir()] == ["fresh.txt"]  # a written folder is replaced whole
    assert [p.name for p in tmp_path.iterdir()] == ["site"]  # the stage is gone


def test_staged_directory_leaves_the_target_untouched_on_error(tmp_path):
    target = tmp_path / "site"
    target.mkdir()
    (target / "a.txt").write_text("a")
    with pytest.raises(RuntimeError), staged_directory(target) as stage:
        (stage / "a.txt").write_text("half")
        raise RuntimeError("boom")
    assert (target / "a.txt").read_text() == "a"
    assert [p.name for p in tmp_path.iterdir()] == ["site"]
