"""The recorder's progress as a topic: the simulated time up to which every stream it waits for
has been taken from DDS, published so that the graph's source (the ship) can keep its lead over
the recorder as it does over the filter (:mod:`alignment_ros.pacing`). Without it nobody waits
for the recorder, and behind a slow recorder its reader queues and the publishers' writer
histories (reliable, KEEP_ALL: a message is held until the recorder acknowledges it) reach new
depths, whose memory DDS keeps for the rest of the run.

The topic is a ``rosgraph_msgs/Clock`` (a time and nothing else), best effort, latest only, and
never recorded. It is published at most every ``period_s`` wall seconds, only when it advanced."""
from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping

from rclpy.node import Node

from alignment_ros import qos
from alignment_ros.topics import msg_class

PROGRESS_TYPE = 'rosgraph_msgs/msg/Clock'
PERIOD_S = 0.02


def progress_ns(last_stamp_ns: Mapping[str, int], streams: Iterable[str]) -> int | None:
    """The oldest of the streams' latest stamps (ns), or None while one has sent nothing."""
    out: int | None = None
    for s in streams:
        t = last_stamp_ns.get(s)
        if t is None:
            return None
        out = t if out is None else min(out, t)
    return out


class ProgressPublisher:
    """Publishes progress_ns(last_stamp_ns, streams) on `topic` when it advanced."""

    def __init__(self, node: Node, topic: str, streams: Iterable[str], last_stamp_ns: Mapping[str, int],
                 period_s: float = PERIOD_S, clock: Callable[[], float] = time.monotonic) -> None:
        self.streams = tuple(streams)
        if not self.streams:
            raise ValueError('the progress needs at least one stream')
        self.last_stamp_ns = last_stamp_ns
        self.period_s = period_s
        self.clock = clock
        self.cls = msg_class(PROGRESS_TYPE)
        self.publisher = node.create_publisher(self.cls, topic, qos.WATCH)
        self.sent_ns = -1
        self.next_s = -float('inf')
        self.published = 0

    def poll(self) -> None:
        """Publish if due and advanced."""
        now = self.clock()
        if now < self.next_s:
            return
        self.next_s = now + self.period_s
        t = progress_ns(self.last_stamp_ns, self.streams)
        if t is None or t <= self.sent_ns:
            return
        msg = self.cls()
        msg.clock.sec, msg.clock.nanosec = divmod(t, 1_000_000_000)
        self.publisher.publish(msg)
        self.sent_ns = t
        self.published += 1
