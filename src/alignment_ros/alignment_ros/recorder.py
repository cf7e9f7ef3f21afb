"""``recorder``: record topics to a rosbag2 MCAP bag (rosbag2 is not available here).

Subscriptions are raw (serialized CDR bytes, no deserialisation) with the STREAM QoS
(RELIABLE + KEEP_ALL), so no message is lost and each costs a few microseconds.

Log time: simulation time, see :mod:`alignment_ros.bag`: the header stamp (read straight from
the CDR bytes), the clock value for ``/clock``, else the latest ``/clock`` value received (before
any ``/clock``: the largest stamp seen so far).

End: the recorder stops at the first of

* ``end_time``: ``--end-time`` is given and every topic of ``--wait-topics`` has received a
  message stamped >= end-time (for a topic without a stamp: its log time); without
  ``--wait-topics``, every topic with a stamp that has received anything must reach it (a
  stream that legitimately stops early, like ``/truth/misalignment`` at the launch, belongs
  outside ``--wait-topics``). It prints ``recorder end-time reached`` and then, with
  ``--expect-counts FILE``, keeps recording until FILE exists (``{topic: count}``: what the
  publishers report they sent, written by the launcher once they have stopped) and every
  recorded topic has received that count; without it, until no message arrived for
  ``--drain`` wall seconds (a guess: a message the transport dropped is resent by the reliable
  protocol only at the writer's next heartbeat, seconds later, and the messages after it on that
  topic wait for it, so a quiet period can end before a slow topic is complete);
* ``incomplete``: ``--expect-counts`` is given and the counts were not all reached within
  ``--expect-timeout`` wall seconds of end-time (the stats list the shortfall as ``missing``);
* ``idle_timeout``: nothing arrived for ``--idle-timeout`` wall seconds after the first message;
* ``signal``: SIGINT or SIGTERM.

While a topic is short of its expected count the recorder also takes from its subscription
directly (not only when the executor dispatches an event), so a message that reached the reader
is never left behind. It then closes the bag (MCAP summary + metadata.yaml) and writes
``--stats``. It prints ``recorder ready`` (one flushed stdout line) once every subscription
exists.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from alignment_ros.bag import BagError, BagWriter, stamp_reader
from alignment_ros.node_util import stop_on_signals
from alignment_ros.qos import STREAM
from alignment_ros.topics import CLOCK, TOPIC_TYPES, msg_class

NS = 1_000_000_000
SPIN_TIMEOUT_S = 0.05


def parse_topic(spec: str) -> tuple[str, str]:
    """'TOPIC' (type from the topic contract) or 'TOPIC=pkg/msg/Type' -> (topic, type)."""
    topic, _, type_name = spec.partition('=')
    if not topic.startswith('/'):
        topic = '/' + topic
    type_name = type_name or TOPIC_TYPES.get(topic, '')
    if not type_name:
        raise argparse.ArgumentTypeError(
            f'{topic} is not in the topic contract: give its type as {topic}=pkg/msg/Type')
    return topic, type_name


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Parse the command line (ROS arguments already removed)."""
    p = argparse.ArgumentParser(prog='recorder', description=__doc__.splitlines()[0])
    p.add_argument('--out', required=True, type=Path, help='bag directory to create (must not exist)')
    p.add_argument('--topics', nargs='+', type=parse_topic, metavar='TOPIC[=TYPE]',
                   help='topics to record (default: every topic of the contract)')
    p.add_argument('--end-time', type=float, metavar='S', help='simulation time (s) to stop at')
    p.add_argument('--wait-topics', nargs='+', default=[], metavar='TOPIC',
                   help='with --end-time: topics that must also reach end-time before stopping')
    p.add_argument('--idle-timeout', type=float, default=5.0, metavar='S',
                   help='stop when nothing arrived for S wall seconds after the first message '
                        '(default 5)')
    p.add_argument('--drain', type=float, default=0.5, metavar='S',
                   help='after end-time is reached, keep recording until S wall seconds are quiet '
                        '(default 0.5)')
    p.add_argument('--expect-counts', type=Path, metavar='FILE',
                   help='after end-time: wait for FILE ({topic: count}, the publishers\' final '
                        'counts) and record until every topic has reached its count (instead of '
                        '--drain)')
    p.add_argument('--expect-timeout', type=float, default=120.0, metavar='S',
                   help='with --expect-counts: give up S wall seconds after end-time '
                        '(end reason incomplete; default 120)')
    p.add_argument('--stats', type=Path, metavar='FILE', help='write counts and end reason as JSON')
    p.add_argument('--executor', choices=('events', 'single'), default='events',
                   help='rclpy executor (default: events, the EventsExecutor)')
    args = p.parse_args(argv)
    if args.out.exists():
        p.error(f'--out {args.out} exists already: the recorder only creates new bags')
    args.topics = dict(args.topics) if args.topics else dict(TOPIC_TYPES)
    for topic, type_name in args.topics.items():
        try:
            stamp_reader(type_name)
            msg_class(type_name)
        except (BagError, ImportError, AttributeError, ValueError) as exc:
            p.error(f'{topic}: unusable message type {type_name!r}: {exc}')
    args.wait_topics = [t if t.startswith('/') else '/' + t for t in args.wait_topics]
    missing = [t for t in args.wait_topics if t not in args.topics]
    if missing:
        p.error(f'--wait-topics not recorded: {", ".join(missing)}')
    if args.expect_counts is not None and args.end_time is None:
        p.error('--expect-counts needs --end-time')
    return args


def read_expected(path: Path) -> dict[str, int] | None:
    """The expected counts ({topic: count}) once the file exists (written atomically), else None."""
    try:
        text = path.read_text()
    except FileNotFoundError:
        return None
    return {str(k): int(v) for k, v in json.loads(text).items()}


class Recorder:
    """Raw subscriptions -> BagWriter, with the end-of-recording bookkeeping."""

    def __init__(self, node: Node, writer: BagWriter, topics: dict[str, str],
                 end_time_s: float | None, wait_topics: list[str]) -> None:
        self.writer = writer
        self.end_ns = None if end_time_s is None else round(end_time_s * NS)
        self.wait_topics = set(wait_topics)
        self.counts = dict.fromkeys(topics, 0)
        self.last_stamp_ns: dict[str, int] = {}
        self.stamped_seen: set[str] = set()  # topics with a stamp that received a message
        self.reached: set[str] = set()  # topics whose last log time >= end-time
        self.clock_ns: int | None = None
        self.max_stamp_ns = 0
        self.first_rx: float | None = None
        self.last_rx: float | None = None
        self.taken_directly = 0  # messages taken by take_pending() rather than by the executor
        self.subscriptions = {}
        self.handlers = {}
        for topic, type_name in topics.items():
            writer.add_topic(topic, type_name)
            self.handlers[topic] = self._callback(topic, type_name)
            self.subscriptions[topic] = node.create_subscription(
                msg_class(type_name), topic, self.handlers[topic], STREAM, raw=True)

    def _callback(self, topic: str, type_name: str) -> Any:
        read_stamp = stamp_reader(type_name)
        is_clock = topic == CLOCK
        write = self.writer.write
        counts = self.counts
        last = self.last_stamp_ns
        end_ns = self.end_ns

        def on_message(data: bytes) -> None:
            if read_stamp is not None:
                t = read_stamp(data)
                if is_clock:
                    if self.clock_ns is None or t > self.clock_ns:
                        self.clock_ns = t
                elif t > self.max_stamp_ns:
                    self.max_stamp_ns = t
                if counts[topic] == 0:
                    self.stamped_seen.add(topic)
            else:
                t = self.clock_ns if self.clock_ns is not None else self.max_stamp_ns
            write(topic, data, t)
            counts[topic] += 1
            if t > last.get(topic, -1):
                last[topic] = t
                if end_ns is not None and t >= end_ns:
                    self.reached.add(topic)
            self.last_rx = time.monotonic()
            if self.first_rx is None:
                self.first_rx = self.last_rx

        return on_message

    def missing(self, expected: dict[str, int]) -> dict[str, int]:
        """Recorded topics that have not yet received their expected count -> shortfall."""
        return {t: n - self.counts[t] for t, n in expected.items()
                if t in self.counts and self.counts[t] < n}

    def take_pending(self, topics: list[str]) -> int:
        """Take every message already in these subscriptions' readers and record it (as the
        executor would), whether or not the executor has an event for it. Returns how many."""
        n = 0
        for topic in topics:
            sub = self.subscriptions[topic]
            while True:
                with sub.handle:
                    info = sub.handle.take_message(sub.msg_type, sub.raw)
                if info is None:
                    break
                self.handlers[topic](info[0])
                n += 1
        self.taken_directly += n
        return n

    def end_time_reached(self) -> bool:
        """True when every --wait-topics topic (or, without any, every stamped topic seen)
        has reached end-time."""
        if self.end_ns is None or not self.stamped_seen:
            return False
        if self.wait_topics:
            return self.wait_topics <= self.reached
        return self.stamped_seen <= self.reached


def make_executor(kind: str) -> Any:
    """EventsExecutor (fast; spin it from the main thread only) or SingleThreadedExecutor."""
    if kind == 'events':
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    return SingleThreadedExecutor()


def run(args: argparse.Namespace, ros_argv: list[str]) -> dict[str, Any]:
    """Record until an end condition; return the stats dict."""
    rclpy.init(args=ros_argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = stop_on_signals()
    node = Node('recorder', parameter_overrides=[Parameter('use_sim_time', value=False)])
    executor = make_executor(args.executor)
    writer = BagWriter(args.out)
    reason = 'error'
    expected: dict[str, int] | None = None
    try:
        rec = Recorder(node, writer, args.topics, args.end_time, args.wait_topics)
        executor.add_node(node)
        print('recorder ready', flush=True)
        end_seen: float | None = None
        while True:
            executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)
            if stop['signal']:
                reason = 'signal'
                break
            now = time.monotonic()
            if end_seen is None and rec.end_time_reached():
                end_seen = now
                print('recorder end-time reached', flush=True)
            if end_seen is not None and args.expect_counts is not None:
                if expected is None:
                    expected = read_expected(args.expect_counts)
                if expected is not None:
                    short = rec.missing(expected)
                    if short and rec.take_pending(list(short)):
                        short = rec.missing(expected)
                    if not short:
                        reason = 'end_time'
                        break
                if now - end_seen >= args.expect_timeout:
                    reason = 'incomplete'
                    break
            elif end_seen is not None:
                quiet_since = max(end_seen, rec.last_rx or end_seen)
                if now - quiet_since >= args.drain or now - end_seen >= max(10 * args.drain, 5.0):
                    reason = 'end_time'
                    break
            elif rec.last_rx is not None and now - rec.last_rx >= args.idle_timeout:
                reason = 'idle_timeout'
                break
    finally:
        writer.close()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    span = (rec.last_rx - rec.first_rx) if rec.first_rx is not None else 0.0
    total = sum(rec.counts.values())
    return {
        'bag': str(args.out),
        'topics': rec.counts,
        'total': total,
        'end_reason': reason,
        'expected': expected,
        'missing': rec.missing(expected or {}),
        'taken_directly': rec.taken_directly,
        'last_stamp_ns': rec.last_stamp_ns,
        'executor': args.executor,
        'receive_span_s': span,
        'receive_rate_msg_s': total / span if span > 0 else None,
    }


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``recorder``."""
    raw_argv = sys.argv if argv is None else ['recorder', *argv]
    args = parse_args(remove_ros_args(raw_argv)[1:])
    try:
        stats = run(args, raw_argv)
    except BagError as exc:
        print(f'recorder: {exc}', file=sys.stderr)
        return 1
    if args.stats:
        args.stats.parent.mkdir(parents=True, exist_ok=True)
        args.stats.write_text(json.dumps(stats, indent=2) + '\n')
    print(f'recorder done ({stats["end_reason"]}): {stats["total"]} messages in {args.out}',
          flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
