"""Some topics of a bag read in one pass and kept: the summary asks one bag for several of its
topics, function by function, and every pass over an MCAP file parses every chunk that holds any
of them (a graph run's chunks hold every topic), so reading each topic on its own costs a pass
over the whole bag each time. :class:`BagTopics` reads the topics it is given together, keeps
their raw messages, and deserialises each topic once, when first asked for."""
from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from rclpy.serialization import deserialize_message

from .bag import BagMessage, BagReader
from .topics import msg_class


class BagTopics:
    """The messages of `topics` in the bag at `path` (log-time order), read at construction
    (BagError if the path is not a bag); a topic the bag does not hold has no messages."""

    def __init__(self, path: str | Path, topics: Iterable[str]) -> None:
        self.path = Path(path)
        self._raw: dict[str, list[BagMessage]] = {t: [] for t in topics}
        self._decoded: dict[str, list] = {}
        for m in BagReader(self.path).messages(list(self._raw)):
            self._raw[m.topic].append(m)

    def __str__(self) -> str:
        return str(self.path)

    def holds(self, topics: Iterable[str]) -> bool:
        """Whether every one of `topics` was read (present in the bag or not)."""
        return all(t in self._raw for t in topics)

    def raw(self, topic: str) -> list[BagMessage]:
        return self._raw[topic]

    def decoded(self, topic: str) -> list:
        """The topic's messages deserialised (the same list on every call: do not modify it)."""
        if topic not in self._decoded:
            self._decoded[topic] = [deserialize_message(m.data, msg_class(m.type_name)) for m in self._raw[topic]]
        return self._decoded[topic]


def topics_of(bag: str | Path | BagTopics, topics: Iterable[str]) -> BagTopics:
    """`bag` itself when it holds `topics`, else those topics read from its path."""
    names = tuple(topics)
    if isinstance(bag, BagTopics):
        return bag if bag.holds(names) else BagTopics(bag.path, names)
    return BagTopics(bag, names)
