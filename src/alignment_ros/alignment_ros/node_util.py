"""Shared node plumbing: start-up with clear config errors, publish counters, stats file,
publishes that wait for slow subscribers instead of failing, clean shutdown on SIGINT/SIGTERM
(held messages sent, every message acknowledged by every reliable subscriber before the process
exits)."""
from __future__ import annotations

import json
import math
import sys
import time
from collections import Counter, defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import rclpy
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import Executor
from rclpy.experimental import EventsExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.node import Node
from rclpy.publisher import Publisher

from alignment_core.validation import ConfigError

from . import params, qos, wire
from .dds_teardown import shut_down
from .heap import map_large_allocations, release_free_heap
from .signals import stop_on_signals

RCLError = rclpy_implementation.RCLError

TRIM_INTERVAL_S = 30.0
"""How often a spinning node hands freed heap back to the OS (alignment_ros/heap.py): the
allocator otherwise keeps each new high-water mark of its input queues in the resident set."""

ACK_TIMEOUT_S = 30.0
"""At shutdown: how long a node waits for its subscribers to acknowledge every message. A
message the transport dropped is resent only at the writer's next heartbeat (Fast DDS: every
3 s); a process that exits before then takes it with it."""

READER_LINGER_S = 0.3
"""At shutdown, after its own messages were acknowledged: how long a node's participant stays,
so that its readers acknowledge what the other nodes sent last, at their writers' next heartbeat
(every 0.1 s, config/dds/fastdds.xml). A writer notices a reader that left with messages
unacknowledged only when that participant's lease expires (20 s), and its node waits that long
at its own end: 12 of 45 default runs ended 20 s late before the nodes lingered, none of 27 since."""

PUBLISH_REFUSED = 'cannot publish data'
"""rmw_fastrtps's error when the DataWriter refuses a write: for a RELIABLE KEEP_ALL writer, its
history is full of messages a reader has not acknowledged yet and none was within
reliability.max_blocking_time (config/dds/fastdds.xml). The message was not taken: sending it
again neither duplicates nor reorders anything."""
PUBLISH_STALL_TIMEOUT_S = 120.0
"""How long `CountingNode.send` retries one refused publish before it gives up. Longer than Fast
DDS's participant lease (20 s): a subscriber that died is unmatched by then and no longer holds
the writer back, so only a reader that is alive and takes nothing for this long ends the node."""


class CountingNode(Node):
    """A node that counts what it publishes and receives and can write them to a JSON file."""

    cpu_ready_s: float | None = None
    """This process's CPU time when the node began to spin (or run): its start-up's, set by run()."""

    executor_ref: Executor
    """The executor that spins the node (an EventsExecutor): set by run() before it spins or runs
    the node (a node that runs its own loop, the ship, spins it from there)."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.published: Counter = Counter()
        self.received: Counter = Counter()
        self.rejected: Counter = Counter()
        self.publish_waits: Counter = Counter()      # publishes refused (writer history full), retried
        self.publish_wait_s: defaultdict[str, float] = defaultdict(float)  # wall seconds spent waiting, per topic
        self.declare_parameter('stats_path', '', ParameterDescriptor(
            description='write publish/receive counts here (JSON) at shutdown; empty: do not'))
        self.declare_parameter('hold_until_matched', [''], ParameterDescriptor(
            description="'topic:count' or 'topic:node+node...' items: hold this node's messages on "
                        "topic until its publisher has matched count subscriptions, or a "
                        "subscription of each node named (no message into the void)"))
        self._pubs: dict[str, Publisher] = {}
        self._need: dict[str, Readers] = parse_readers(self.get_parameter('hold_until_matched').value)
        self._held: dict[str, list] = {}
        self._all_acked: bool | None = None   # set by wait_acked()
        self._ack_wait_s: float | None = None    # and how long it waited (all calls)
        self._next_trim = time.monotonic() + TRIM_INTERVAL_S
        if self._need:
            # held messages go out as soon as their subscribers match, even when nothing else
            # is sent any more (a steady clock: simulation time may have stopped)
            self.create_timer(0.05, self.flush_held, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def release_heap_if_due(self) -> None:
        """Hand freed heap back to the OS every TRIM_INTERVAL_S (a spinning node's loop calls it;
        a node that runs its own loop, the ship, calls it from there)."""
        now = time.monotonic()
        if now >= self._next_trim:
            release_free_heap()
            self._next_trim = now + TRIM_INTERVAL_S

    def stream_publisher(self, msg_type, topic: str) -> Publisher:
        pub = self.create_publisher(msg_type, topic, qos.STREAM)
        self._pubs[topic] = pub
        return pub

    def stream_subscription(self, msg_type, topic: str, callback: Callable[[Any], None],
                            on_malformed: Callable[[str], None] | None = None):
        """Subscribe to a stream (qos.STREAM) as bytes and hand `callback` the message read from
        them (alignment_ros/wire.py: rosbags' dataclass of msg_type, the same fields). Bytes that are
        not such a message are rejected: counted under 'malformed <topic>' in `rejected`, logged (at
        most once a second per topic), passed to `on_malformed` (with the topic) if given, and the
        node goes on."""
        read = wire.reader(msg_type)
        key = f'malformed {topic}'
        logged = [-math.inf]                  # when this topic's last rejection was logged (once a second)

        def on_bytes(raw: bytes) -> None:
            try:
                msg = read(raw)
            except wire.MalformedMessageError as e:
                self.rejected[key] += 1
                now = time.monotonic()
                if now - logged[0] >= 1.0:
                    logged[0] = now
                    self.get_logger().error(f'{topic}: rejected a malformed message ({e}); '
                                            f'{self.rejected[key]} so far')
                if on_malformed is not None:
                    on_malformed(topic)
                return
            callback(msg)
        return self.create_subscription(msg_type, topic, on_bytes, qos.STREAM, raw=True)

    def _matched(self, topic: str) -> bool:
        """The topic's publisher has the subscriptions it waits for (see readers_matched)."""
        pub = self._pubs.get(topic)
        if pub is None:
            return False
        count, names = self._need[topic]
        return readers_matched(self, topic, pub.get_subscription_count(), count, names)

    def send(self, topic: str, msg) -> None:
        need = self._need.get(topic)
        if need is not None:
            if not self._matched(topic):
                self._held.setdefault(topic, []).append(msg)
                return
            del self._need[topic]
            for m in self._held.pop(topic, []):
                self._publish_or_wait(topic, m)
        self._publish_or_wait(topic, msg)

    def _publish_or_wait(self, topic: str, msg) -> None:
        """Publish and count. While the transport refuses the message (PUBLISH_REFUSED: the
        writer's history is full and no subscriber acknowledged within max_blocking_time), wait
        and publish it again, backing off to 0.1 s, for up to PUBLISH_STALL_TIMEOUT_S. Nothing is
        dropped or reordered: the caller does not go on before this message is taken."""
        pub = self._pubs[topic]
        t0: float | None = None
        pause = 0.001
        while True:
            try:
                pub.publish(msg)
                break
            except RCLError as e:
                if PUBLISH_REFUSED not in str(e):
                    raise
                now = time.monotonic()
                t0 = now if t0 is None else t0
                self.publish_waits[topic] += 1
                if now - t0 > PUBLISH_STALL_TIMEOUT_S:
                    raise RuntimeError(
                        f'{topic}: a subscriber acknowledged nothing for {now - t0:.0f} s; '
                        f'message {self.published[topic] + 1} could not be published') from e
                time.sleep(pause)
                pause = min(2.0 * pause, 0.1)
        if t0 is not None:
            self.publish_wait_s[topic] += time.monotonic() - t0
        self.published[topic] += 1

    def flush_held(self) -> None:
        """Publish held messages of every topic whose subscribers have now matched."""
        for topic in list(self._need):
            if self._matched(topic):
                del self._need[topic]
                for m in self._held.pop(topic, []):
                    self._publish_or_wait(topic, m)

    def held(self) -> dict[str, int]:
        """Messages still held back because their subscribers never matched."""
        return {t: len(v) for t, v in self._held.items() if v}

    def wait_acked(self, timeout_s: float = 10.0) -> bool:
        """Block until every reliable subscriber has acknowledged every message published so far
        (all publishers together within timeout_s). False if some were not."""
        ok = True
        t0 = time.monotonic()
        deadline = t0 + timeout_s
        for pub in self._pubs.values():
            left = max(0.0, deadline - time.monotonic())
            try:
                ok &= bool(pub.wait_for_all_acked(rclpy.duration.Duration(seconds=left)))
            except Exception:   # not supported by every RMW
                pass
        self._all_acked = ok
        self._ack_wait_s = (self._ack_wait_s or 0.0) + time.monotonic() - t0
        return ok

    def stats(self) -> dict:
        return {'node': self.get_name(), 'published': dict(self.published),
                'received': dict(self.received), 'rejected': dict(self.rejected),
                'held_unsent': self.held(), 'all_acked': self._all_acked,
                'ack_wait_s': None if self._ack_wait_s is None else round(self._ack_wait_s, 3),
                'publish_waits': dict(self.publish_waits),
                'publish_wait_s': {t: round(v, 3) for t, v in self.publish_wait_s.items()},
                'cpu_s': time.process_time(), 'cpu_ready_s': self.cpu_ready_s}

    def write_stats(self) -> None:
        path = self.get_parameter('stats_path').value
        if path:
            Path(path).write_text(json.dumps(self.stats(), indent=1))



Readers = tuple[int, tuple[str, ...]]
"""What a topic waits for: a count of matched subscriptions, and nodes that must be among them."""


def parse_readers(items) -> dict[str, Readers]:
    """{topic: (count, node names)} of 'topic:count' and 'topic:node+node...' items (a list of
    names counts as that many subscriptions); empty items are skipped."""
    out: dict[str, Readers] = {}
    for item in items:
        if not item:
            continue
        topic, _, what = item.rpartition(':')
        if not topic or not what:
            raise ConfigError(f"'{item}': expected 'topic:count' or 'topic:node+node...'")
        if what.isdigit():
            out[topic] = (int(what), ())
        else:
            names = tuple(n for n in what.split('+') if n)
            out[topic] = (len(names), names)
    return out


def readers_matched(node: Node, topic: str, matched: int, count: int, names: tuple[str, ...]) -> bool:
    """`matched` subscriptions (a publisher's count) reach `count` and, when nodes are named,
    each of them has a subscription on the topic and every subscription discovered on it is
    matched. A count alone can be met by a subscriber nobody waits for (echo.sh, a second
    recorder) while one that is waited for is still being discovered: it would miss the start."""
    if matched < count:
        return False
    if not names:
        return True
    infos = node.get_subscriptions_info_by_topic(topic)
    have = {i.node_name for i in infos}
    return matched >= len(infos) and all(n in have for n in names)


def _refuse(message: str) -> None:
    """Start-up error: one line on stderr, exit status 2."""
    print(message, file=sys.stderr, flush=True)
    rclpy.try_shutdown()
    sys.exit(2)


def run(node_factory, spin: bool = True) -> None:
    """Create the node (invalid, unknown or wrong-typed parameters exit with status 2 and a
    one-line reason), spin until SIGINT/SIGTERM, then send what is held, wait until every
    subscriber has acknowledged every message (ACK_TIMEOUT_S), write stats, let its readers
    acknowledge the others' last messages (READER_LINGER_S) and shut down.

    The EventsExecutor dispatches several times faster than the wait-set executors; it is
    spun from the main thread only (it runs no callbacks from a background thread)."""
    map_large_allocations()
    try:
        rclpy.init(args=sys.argv)
    except RCLError as e:              # a -p rule rcl cannot parse
        hint = (' (a list takes one type: write [1.0, 2.5], not [1, 2.5])'
                if 'Sequence should be of same type' in str(e) else '')
        _refuse(f'invalid arguments: {str(e).split(", at ")[0]}{hint}')
    try:
        node = node_factory()
        params.refuse_unknown(node)
    except ConfigError as e:
        _refuse(f'invalid configuration: {e}')
    except (InvalidParameterTypeException, InvalidParameterValueException) as e:
        _refuse(f'invalid configuration: {e}')   # a node parameter of the wrong type or value
    stop = stop_on_signals()
    executor = EventsExecutor()
    executor.add_node(node)
    node.executor_ref = executor
    failed = True          # an exception on its way out: a stuck teardown ends with status 1
    node.cpu_ready_s = time.process_time()
    try:
        if spin:
            while rclpy.ok() and not stop['signal']:
                executor.spin_once(timeout_sec=0.1)
                node.release_heap_if_due()
        else:
            node.run(lambda: stop['signal'])
        failed = False
    finally:
        if hasattr(node, 'finish'):
            node.finish()
        deadline = time.monotonic() + 5.0
        while node.held() and time.monotonic() < deadline:
            node.flush_held()
            executor.spin_once(timeout_sec=0.05)
        if not node.wait_acked(ACK_TIMEOUT_S):
            node.get_logger().warning(
                f'not every message was acknowledged within {ACK_TIMEOUT_S:.0f} s')
        node.write_stats()
        time.sleep(READER_LINGER_S)
        shut_down(node, status=1 if failed else 0, signalled=stop['signal'])
