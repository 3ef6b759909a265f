"""An open ROS bag (ROS 1 .bag, ROS 2 folder, .db3 or .mcap) read with rosbags: its topics and its
messages deserialised, message definitions registered where the bag lacks them."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from bimkit.documents import check_regular
from bimkit.errors import InputError
from bimkit.limits import MAX_BAG_BYTES
from initcli.ros.msgdefs import (
    VISION_MSGS_LAYOUTS,
    detect_layout,
    register_missing,
    ros2_typestore,
    with_layout,
)
from initcli.ros.records import Topic

__all__ = ["BagSource", "PROBED", "bag_paths"]

PROBED = 50  # messages of a topic without definitions tried in each vision_msgs layout


def bag_paths(path: Path) -> list[Path]:
    """What rosbags opens for ``path``: a ROS 1 .bag, a ROS 2 bag folder or a bare .mcap file."""
    if not path.exists():
        raise InputError(f"{path}: no such bag")
    if path.is_file() and path.suffix == ".db3":
        return [path.parent]  # a ROS 2 sqlite3 file: its folder holds the metadata
    if path.is_dir() and not (path / "metadata.yaml").exists():
        mcaps = sorted(path.glob("*.mcap"))
        if len(mcaps) == 1:
            return mcaps
        raise InputError(f"{path}: a folder without metadata.yaml; expected a ROS 2 bag folder")
    if not path.is_dir():
        check_regular(path, "a ROS bag (.bag, .mcap or .db3)", MAX_BAG_BYTES)
    return [path]


class BagSource:
    """An open bag: its topics, and its messages deserialised (definitions registered if missing)."""

    def __init__(self, path: Path | str) -> None:
        from rosbags.highlevel import AnyReader

        self.path = Path(path)
        try:
            self.reader = AnyReader(bag_paths(self.path), default_typestore=ros2_typestore())
            self.reader.open()
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001 - rosbags raises many types for a bad file
            raise InputError(f"{self.path}: not a readable ROS bag ({_first_line(exc)})") from None
        try:
            register_missing(self.reader.typestore, {c.msgtype for c in self.reader.connections})
            self.vision_layout = self._vision_layout()
        except BaseException:
            self.reader.close()
            raise
        self.topics: dict[str, Topic] = {}
        for c in self.reader.connections:
            old = self.topics.get(c.topic)
            self.topics[c.topic] = Topic(c.topic, c.msgtype, (old.count if old else 0) + c.msgcount)

    def _vision_layout(self) -> str | None:
        """The ``vision_msgs`` layout of a ROS 2 bag that carries no definitions of them (a
        ``.db3`` of Foxy or Humble): the one its messages parse in, put in the reader's typestore.
        None: the bag's own definitions (or no vision_msgs)."""
        from rosbags.interfaces import MessageDefinitionFormat

        bundled = [
            c
            for c in self.reader.connections
            if c.msgtype.startswith("vision_msgs/") and c.msgdef.format == MessageDefinitionFormat.NONE
        ]
        if not bundled or not self.reader.is2:
            return None
        for conn in bundled:
            messages = self.reader.messages(connections=[conn])
            raws = (raw for _, (_, _, raw) in zip(range(PROBED), messages, strict=False))
            layout = detect_layout(raws, conn.msgtype)
            if layout is None:
                raise InputError(
                    f"{self.path}: {conn.topic}: the {conn.msgtype} messages carry no definition and parse "
                    f"in no known vision_msgs layout ({', '.join(VISION_MSGS_LAYOUTS)})"
                )
            if layout != "humble":
                self.reader.typestore = with_layout(self.reader.typestore, layout)
                return layout
        return "humble"

    def close(self) -> None:
        self.reader.close()

    def __enter__(self) -> BagSource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.topics.values())

    def messages(self, topics: Iterable[str]) -> Iterator[tuple[str, int, Any]]:
        """(topic, bag time ns, message) in bag time order."""
        wanted = set(topics)
        conns = [c for c in self.reader.connections if c.topic in wanted]
        if not conns:
            return
        topic = ""
        try:
            for conn, stamp, raw in self.reader.messages(connections=conns):
                topic = conn.topic
                yield conn.topic, stamp, self.reader.deserialize(raw, conn.msgtype)
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001
            where = f"{topic}: " if topic else ""
            raise InputError(f"{self.path}: {where}cannot read a message ({_first_line(exc)})") from None

    def first(self, topic: str) -> Any | None:
        for _, _, msg in self.messages([topic]):
            return msg
        return None


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
