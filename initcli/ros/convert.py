"""A recorded ROS bag or a CARMEN laser log as a detection log (``bim-init bag2log``), and a log, a
bag or a CARMEN log taken alike (``bim-init match``): no ROS needed."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from bimkit.errors import InputError
from initcli.io.carmen import CarmenStats, carmen_to_records, is_carmen
from initcli.io.detection_log import Record
from initcli.io.log_writer import write_log
from initcli.ros.records import Bag2LogOptions, Bag2LogStats

if TYPE_CHECKING:
    from initcli.ros.bag_reader import Progress

__all__ = ["BAG_SUFFIXES", "convert_bag", "is_bag", "log_or_bag"]


def convert_bag(
    bag: Path, out: Path, options: Bag2LogOptions, progress: Progress | None = None
) -> tuple[list[Record], Bag2LogStats | CarmenStats]:
    """Read ``bag`` (a ROS bag or a CARMEN laser log) and write the log to ``out`` atomically;
    ``progress(done, total)`` after each message of a bag read."""
    stats: Bag2LogStats | CarmenStats
    if is_carmen(bag):
        records, stats = carmen_to_records(bag)
    else:
        from initcli.ros.bag_reader import bag_to_records  # rosbags, only when a bag is read

        records, stats = bag_to_records(bag, options, progress)
    out = Path(out)
    tmp = out.with_name(f".{out.name}.partial")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        write_log(tmp, records)
        tmp.replace(out)
    except BaseException as exc:  # Ctrl-C or SIGTERM too: no half log left behind
        with contextlib.suppress(OSError):  # a parent that is a file: there is nothing to remove
            tmp.unlink(missing_ok=True)
        if not isinstance(exc, OSError | ValueError):  # ValueError: a number no log holds (NaN)
            raise
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise InputError(f"{out}: cannot write the log: {why}") from None
    return records, stats


BAG_SUFFIXES = (".bag", ".mcap", ".db3")


def is_bag(path: Path) -> bool:
    """A ROS bag rather than a detection log: .bag, .mcap, .db3, or a ROS 2 bag folder."""
    return path.suffix.lower() in BAG_SUFFIXES or (path.is_dir() and (path / "metadata.yaml").exists())


@contextmanager
def log_or_bag(
    path: Path, options: Bag2LogOptions | None = None, progress: Progress | None = None
) -> Iterator[Path]:
    """``path`` itself for a detection log; for a bag, the log converted into a temporary folder
    (an error about that log names the bag, not the temporary file); a CARMEN laser log alike."""
    if not is_bag(Path(path)) and not is_carmen(Path(path)):
        yield Path(path)
        return
    with tempfile.TemporaryDirectory(prefix="bim-init-bag2log-") as tmp:
        log = Path(tmp) / f"{Path(path).name.split('.')[0] or 'log'}.jsonl"
        convert_bag(Path(path), log, options or Bag2LogOptions(), progress)
        try:
            yield log
        except InputError as exc:
            raise InputError(str(exc).replace(str(log), f"{path} (as a detection log)")) from None
