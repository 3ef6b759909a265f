"""initcli.cli.bag2log called directly: is_bag, log_or_bag."""

from __future__ import annotations

from pathlib import Path

from initcli.cli.bag2log import is_bag, log_or_bag


def test_is_bag(tmp_path: Path) -> None:
    assert is_bag(Path("x.bag")) and is_bag(Path("x.MCAP")) and is_bag(Path("x.db3"))
    assert not is_bag(Path("x.jsonl"))
    folder = tmp_path / "rec"
    folder.mkdir()
    assert not is_bag(folder)
    (folder / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    assert is_bag(folder)


def test_log_or_bag_passes_a_log_through(tmp_path: Path) -> None:
    log = tmp_path / "session.jsonl"
    with log_or_bag(log) as path:
        assert path == log
