"""``recorder``: ``ros2 bag record`` for this project (rosbag2 is not available here).

Options and topic selection: :mod:`alignment_ros.record_options`. Topics are discovered from
the graph every ``--polling-interval`` ms (``get_topic_names_and_types``), so any topic of an
installed type can be recorded; a subscription asks what the publishers offer (reliable only if
all are, transient-local only if all are) with KEEP_ALL history, and a topic given with its type
(or one of the project's) is subscribed at once with the STREAM QoS (RELIABLE + KEEP_ALL).
Subscriptions are raw (CDR bytes, no deserialisation): no message is lost and each costs a few
microseconds. The bag (:mod:`alignment_ros.bag_writer`) stores the publishers' offered QoS and
type hash, taken from the graph when a topic's first message arrives.

Log time: simulation time, see :mod:`alignment_ros.bag`.

End: the recorder stops at the first of

* ``signal``: SIGINT or SIGTERM (``ros2 bag record``'s only end); what already reached the
  subscriptions' readers is still recorded;
* ``end_time``: ``--end-time`` is given and every topic of ``--wait-topics`` has received a
  message stamped >= end-time (for a topic without a stamp: its log time); without
  ``--wait-topics``, every topic with a stamp that has received anything must reach it. It
  prints ``recorder end-time reached`` and then, with ``--expect-counts FILE``, keeps recording
  until FILE exists (``{topic: count}``: what the publishers report they sent, written by the
  launcher once they have stopped) and every recorded topic has that count; without it, until
  no message arrived for ``--drain`` wall seconds (a guess: a message the transport dropped is
  resent only at the writer's next heartbeat, seconds later);
* ``incomplete``: ``--expect-counts`` is given and the counts were not all reached within
  ``--expect-timeout`` wall seconds of end-time (the stats list the shortfall as ``missing``);
* ``idle_timeout``: ``--idle-timeout`` S > 0 and nothing arrived for S wall seconds after the
  first message.

The publishers of every recorded topic are looked up in the graph every second; the stats list
them (``publishers``: topic -> {node: how many distinct publishers it had there}), so a launcher
can tell a message from a publisher that is not one of its run's.

While a topic is short of its expected count the recorder also takes from its subscription
directly (nothing that reached a reader is left behind), then closes the bag and writes
``--stats`` (``reorder``: see :mod:`alignment_ros.bag_reorder`). It prints ``recorder ready``
once the first subscriptions exist. ``--progress-topic``: :mod:`alignment_ros.record_progress`.
"""
from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from alignment_ros.bag import BagError, BagWriter, stamp_reader
from alignment_ros.bag_qos import adapted_qos, endpoints_hash, qos_dict
from alignment_ros.heap import map_large_allocations, release_free_heap
from alignment_ros.progress import Progress
from alignment_ros.qos import STREAM
from alignment_ros.record_options import TopicFilter, parse_args
from alignment_ros.record_progress import ProgressPublisher
from alignment_ros.record_stats import read_expected, recording_stats, report
from alignment_ros.topics import CLOCK, msg_class

from .dds_teardown import say_once, shut_down
from .signals import stop_on_signals

NS = 1_000_000_000
SPIN_TIMEOUT_S = 0.05
FLUSH_INTERVAL_S = 0.5  # the spool reaches the disk this often (what a killed recorder keeps)
PUBLISHERS_INTERVAL_S = 1.0  # the recorded topics' publishers are looked up this often
DISCOVERY_SETTLE_S = 1.0  # wall s without a new topic before a discovering recording lets its bag go (settle)
TRIM_INTERVAL_S = 30.0  # freed heap (the reorder buffer's peaks) handed back to the OS this often
WALL_STAMPED = ('/rosout', '/parameter_events')   # rcl stamps these with the wall clock
UNKNOWN_NODE = '_NODE_NAME_UNKNOWN_'  # rmw's name of a node not yet discovered


def info(text: str) -> None:
    """A log line on stderr (stdout carries the lines the launcher waits for)."""
    print(f'[INFO] [recorder]: {text}', file=sys.stderr, flush=True)


class Recorder:
    """Raw subscriptions -> BagWriter, topic discovery, and the end-of-recording bookkeeping."""

    def __init__(self, node: Node, writer: BagWriter, topics: dict[str, str],
                 end_time_s: float | None, wait_topics: list[str], *,
                 topic_filter: TopicFilter | None = None, use_sim_time: bool = False) -> None:
        self.node = node
        self.writer = writer
        self.filter = topic_filter
        self.use_sim_time = use_sim_time
        self.end_ns = None if end_time_s is None else round(end_time_s * NS)
        self.wait_topics = set(wait_topics)
        self.counts: dict[str, int] = {}
        self.last_stamp_ns: dict[str, int] = {}
        self.stamped_seen: set[str] = set()  # topics with a stamp that received a message
        self.reached: set[str] = set()  # topics whose last log time >= end-time
        self.clock_ns: int | None = None
        self.max_stamp_ns = 0
        self.first_rx: float | None = None
        self.first_rx_unix: float | None = None    # wall clock, for a launcher's start-up time
        self.first_rx_cpu_s: float | None = None   # this process's CPU time then (its start-up's)
        self.last_rx: float | None = None
        self.taken_directly = 0  # messages taken by take_pending() rather than by the executor
        self.subscriptions: dict[str, Any] = {}
        self.handlers: dict[str, Any] = {}
        self._endpoints_known: set[str] = set()
        self._unusable: set[str] = set()
        self._publisher_names: dict[str, dict[str, str]] = {}   # topic -> {endpoint GID: node}
        self.last_new_topic = time.monotonic()     # when discovery last subscribed to a topic
        for topic, type_name in topics.items():
            self.subscribe(topic, type_name, STREAM)

    def subscribe(self, topic: str, type_name: str, qos: QoSProfile) -> None:
        """Add the topic to the bag, then subscribe (so no callback meets an unknown topic)."""
        self.writer.add_topic(topic, type_name)
        self.counts[topic] = 0
        self.handlers[topic] = self._callback(topic, type_name)
        self.subscriptions[topic] = self.node.create_subscription(
            msg_class(type_name), topic, self.handlers[topic], qos, raw=True)
        info(f"Subscribed to topic '{topic}'")

    def discover(self) -> int:
        """Subscribe to the graph's new topics that the filter selects; return how many."""
        if self.filter is None:
            return 0
        n = 0
        for topic, types in self.node.get_topic_names_and_types():
            if topic in self.subscriptions or topic in self._unusable or len(set(types)) != 1:
                continue
            if not self.filter.take(topic, types[0]):
                continue
            pubs = self.node.get_publishers_info_by_topic(topic)
            if not pubs and not self.filter.include_unpublished:
                continue
            try:
                msg_class(types[0])
            except (ImportError, AttributeError, ValueError):
                self._unusable.add(topic)
                info(f"Topic '{topic}' has unknown type '{types[0]}': not recorded")
                continue
            self.subscribe(topic, types[0], adapted_qos(pubs))
            n += 1
        if n:
            self.last_new_topic = time.monotonic()
        return n

    def settle(self, discovering: bool, now: float) -> None:
        """Hold the bag's reorder buffer while discovery may still add topics: until none appeared for
        DISCOVERY_SETTLE_S (the graph's nodes start within about a second of each other) and while a
        named topic is missing. A topic subscribed late cannot hold back what went out before it."""
        recent = self.filter is not None and self.filter.discovers() and now - self.last_new_topic < DISCOVERY_SETTLE_S
        self.writer.reorder.hold = discovering and (recent or bool(self.pending_topics()))

    def pending_topics(self) -> list[str]:
        """Topics named on the command line that are not subscribed yet."""
        return [t for t in (self.filter.topics if self.filter else []) if t not in self.subscriptions]

    def record_endpoints(self, topic: str) -> None:
        """Store the publishers' offered QoS and type hash for the topic (once, when known)."""
        infos = self.node.get_publishers_info_by_topic(topic)
        if infos:
            self.writer.set_topic_endpoints(topic, [qos_dict(i.qos_profile) for i in infos],
                                            endpoints_hash(infos))
            self._endpoints_known.add(topic)

    def note_publishers(self) -> None:
        """Remember the publishers of each recorded topic (by endpoint GID, with the node name
        once the graph knows it): a launcher compares them with its own nodes."""
        for topic in self.subscriptions:
            seen = self._publisher_names.setdefault(topic, {})
            for i in self.node.get_publishers_info_by_topic(topic):
                name = i.node_namespace.rstrip('/') + '/' + i.node_name
                gid = bytes(i.endpoint_gid).hex()
                if gid not in seen or UNKNOWN_NODE not in name:
                    seen[gid] = name

    def publishers(self) -> dict[str, dict[str, int]]:
        """topic -> {node: how many distinct publishers it had on the topic}."""
        return {t: dict(Counter(seen.values())) for t, seen in self._publisher_names.items()}

    def _sim_now(self) -> int:
        return self.node.get_clock().now().nanoseconds if self.use_sim_time else 0

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
                t = self.clock_ns if self.clock_ns is not None else (
                    self._sim_now() or self.max_stamp_ns)
            if counts[topic] == 0 and topic not in self._endpoints_known:
                self.record_endpoints(topic)
            write(topic, data, t)
            counts[topic] += 1
            if t > last.get(topic, -1):
                last[topic] = t
                if end_ns is not None and t >= end_ns:
                    self.reached.add(topic)
            self.last_rx = time.monotonic()
            if self.first_rx is None:
                self.first_rx, self.first_rx_unix = self.last_rx, time.time()
                self.first_rx_cpu_s = time.process_time()

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
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
                if taken is None:
                    break
                self.handlers[topic](taken[0])
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

    def finish_endpoints(self) -> None:
        """Offered QoS of topics that never received a message (their publishers, if any)."""
        for topic in self.subscriptions:
            if topic not in self._endpoints_known:
                self.record_endpoints(topic)


def make_executor(kind: str) -> Any:
    """EventsExecutor (fast; spin it from the main thread only) or SingleThreadedExecutor."""
    if kind == 'events':
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    return SingleThreadedExecutor()


def _loop(args: argparse.Namespace, rec: Recorder, executor: Any, stop: dict[str, bool],
          progress: Progress, reached: ProgressPublisher | None) -> tuple[str, dict[str, int] | None]:
    """Spin until an end condition; return (end reason, expected counts)."""
    interval = max(args.polling_interval, 1) / 1000.0
    discovering = not args.no_discovery and (args.filter.discovers() or bool(rec.pending_topics()))
    next_poll = time.monotonic() + interval
    next_flush = time.monotonic() + FLUSH_INTERVAL_S
    next_publishers = next_trim = time.monotonic()
    end_seen: float | None = None
    expected: dict[str, int] | None = None
    rec.settle(discovering, time.monotonic())
    while True:
        executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)
        if reached is not None:
            reached.poll()
        if stop['signal']:
            rec.take_pending(list(rec.subscriptions))   # delivered before the signal: keep it
            return 'signal', expected
        now = time.monotonic()
        if now >= next_flush:
            rec.writer.flush()
            next_flush = now + FLUSH_INTERVAL_S
        if now >= next_publishers:
            rec.note_publishers()
            next_publishers = now + PUBLISHERS_INTERVAL_S
            _progress(rec, progress, args.progress_lines)
        if now >= next_trim:
            release_free_heap()
            next_trim = now + TRIM_INTERVAL_S
        if discovering and now >= next_poll:
            rec.discover()
            discovering = args.filter.discovers() or bool(rec.pending_topics())
            next_poll = now + interval
        rec.settle(discovering, now)
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
                    return 'end_time', expected
            if now - end_seen >= args.expect_timeout:
                return 'incomplete', expected
        elif end_seen is not None:
            quiet_since = max(end_seen, rec.last_rx or end_seen)
            if now - quiet_since >= args.drain or now - end_seen >= max(10 * args.drain, 5.0):
                return 'end_time', expected
        elif (args.idle_timeout > 0 and rec.last_rx is not None
              and now - rec.last_rx >= args.idle_timeout):
            return 'idle_timeout', expected


def _reached_ns(rec: Recorder) -> int:
    if rec.clock_ns is not None:
        return rec.clock_ns
    return max((t for k, t in rec.last_stamp_ns.items() if k in rec.stamped_seen and k not in WALL_STAMPED),
               default=0)


def _progress(rec: Recorder, progress: Progress, lines: bool) -> None:
    """The progress line (stderr) and, for a launcher, 'recorder progress MESSAGES STAMP_NS': the
    time reached is /clock's when recorded, else the latest stamp of a topic whose messages carry
    one, but for those rcl stamps with the wall clock (/rosout, /parameter_events)."""
    t_ns, total = _reached_ns(rec), sum(rec.counts.values())
    progress.update(t_ns / NS if t_ns else None, messages=total)
    if lines:
        print(f'recorder progress {total} {t_ns}', flush=True)


def run(args: argparse.Namespace, ros_argv: list[str],
        report: Callable[[dict[str, Any]], None] = lambda stats: None) -> dict[str, Any]:
    """Record until an end condition; return the stats dict, given to `report` first, while the
    node still exists (its teardown is bounded: dds_teardown.py)."""
    writer = BagWriter(args.output, max_bag_duration_s=args.max_bag_duration,
                       max_bag_size=args.max_bag_size, compression_mode=args.compression_mode,
                       compression_format=args.compression_format, custom_data=args.custom_data)
    map_large_allocations()
    rclpy.init(args=ros_argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = stop_on_signals()
    node = Node(args.node_name, parameter_overrides=[
        Parameter('use_sim_time', value=bool(args.use_sim_time))])
    executor = make_executor(args.executor)
    reason = 'error'
    expected: dict[str, int] | None = None
    rec: Recorder | None = None
    reached: ProgressPublisher | None = None
    try:
        try:
            rec = Recorder(node, writer, args.typed, args.end_time, args.wait_topics,
                           topic_filter=args.filter, use_sim_time=args.use_sim_time)
            executor.add_node(node)
            rec.discover()
            print('recorder ready', flush=True)
            progress = Progress('record', None, quiet=args.quiet)
            if args.progress_topic is not None:
                reached = ProgressPublisher(node, args.progress_topic, args.wait_topics, rec.last_stamp_ns)
            reason, expected = _loop(args, rec, executor, stop, progress, reached)
            t_ns = _reached_ns(rec)
            progress.close(t_ns / NS if t_ns else None, sum(rec.counts.values()))
        finally:
            if rec is not None:
                rec.finish_endpoints()
                rec.note_publishers()
            writer.close()
        stats = recording_stats(args, rec, writer, reason, expected, reached)
        report(stats)
    except BaseException as exc:
        if isinstance(exc, BagError):      # its line before a teardown that might not end
            say_once(exc, f'recorder: {exc}')
        shut_down(node, executor, status=1, signalled=stop['signal'])
        raise
    shut_down(node, executor, status=0, signalled=stop['signal'])
    return stats


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``recorder`` (scripts/record.sh)."""
    raw_argv = sys.argv if argv is None else ['recorder', *argv]
    args = parse_args(remove_ros_args(raw_argv)[1:])
    try:
        run(args, raw_argv, lambda stats: report(args, stats))
    except BagError as exc:
        say_once(exc, f'recorder: {exc}')
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
