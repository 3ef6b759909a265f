"""initcli.ros.convert: is_bag, log_or_bag, convert_bag."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks._recordings import make_recording, write
from bimkit.errors import InputError
from initcli.io.detection_log import read_log
from initcli.ros.convert import convert_bag, is_bag, log_or_bag
from initcli.ros.records import Bag2LogOptions


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


def test_convert_bag_writes_the_log_atomically(tmp_path: Path) -> None:
    bag = write(tmp_path, make_recording(duration=1.0, numeric=True), "mcap")
    out = tmp_path / "logs" / "rec.jsonl"
    records, stats = convert_bag(bag, out, Bag2LogOptions(class_names=("door", "lift", "stairs")))
    log = read_log(out)
    assert stats.images == len(log.detections) > 0
    assert len(log.odom) == stats.odom > 0
    assert len(records) >= stats.images + stats.odom
    assert not list(out.parent.glob(".*.partial"))


def test_log_or_bag_converts_a_bag_into_a_temporary_log(tmp_path: Path) -> None:
    bag = write(tmp_path, make_recording(duration=1.0), "mcap")
    with log_or_bag(bag) as path:
        assert path.suffix == ".jsonl" and path.parent != bag.parent
        assert read_log(path).odom
    assert not path.exists()


def test_convert_bag_onto_a_folder_is_input_error_and_leaves_no_partial(tmp_path: Path) -> None:
    bag = write(tmp_path, make_recording(duration=1.0), "mcap")
    out = tmp_path / "taken.jsonl"
    out.mkdir()
    with pytest.raises(InputError, match="cannot write the log"):
        convert_bag(bag, out, Bag2LogOptions())
    assert out.is_dir() and not (tmp_path / ".taken.jsonl.partial").exists()


def test_convert_bag_under_a_file_is_input_error(tmp_path: Path) -> None:
    bag = write(tmp_path, make_recording(duration=1.0), "mcap")
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(InputError, match="cannot write the log"):
        convert_bag(bag, blocker / "sub" / "x.jsonl", Bag2LogOptions())
