"""``player BAG``: ``ros2 bag play`` (Jazzy) for rosbag2 MCAP bags (rosbag2 is not installed here).

Plays like rosbag2's player: messages as stored (serialized CDR bytes) in log-time order, each
at ``start + (t - start) / rate`` on a steady clock, ``start`` being the bag's first log time
plus ``--start-offset``; ``--playback-duration`` / ``--playback-until-*`` end it (the later of
the two), ``--loop`` starts again after ``--delay``; topics selected by ``--topics``,
``--exclude-topics``, ``-e``/``-x`` (full-match regular expressions) as rosbag2 selects them;
``--remap old:=new``; ``--clock HZ`` publishes the player's clock on /clock (the bag's /clock is
then not played). Each topic is offered the QoS it was recorded with, history KEEP_LAST 10, unless
``--qos-profile-overrides-path`` says otherwise (alignment_ros.bag_qos).

Extensions (play_options.py): ``--rate 0`` (no pacing), ``--lossless`` (RELIABLE + KEEP_ALL, and
wait for every acknowledgement at the end), ``--wait-subscribers TOPIC=N``, ``--stats FILE``.
scripts/replay.sh plays with ``--rate 0 --lossless``: as fast as the filter takes it, nothing lost.

A truncated bag plays its readable prefix (warning on stderr, ``"truncated": true`` in the
stats). Exit status: 0 (also after Ctrl-C), 1 for a path that is not a bag, an unusable QoS
overrides file or subscribers not matched in time, 2 for a usage error.
"""
from __future__ import annotations

import argparse
import json
import logging
import re
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSDurabilityPolicy, QoSHistoryPolicy, QoSProfile, QoSReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rclpy.time import Time
from rosgraph_msgs.msg import Clock

from alignment_ros.bag import BagError, BagReader
from alignment_ros.bag_qos import QoSOverrideError, adapt_recorded, load_overrides, recorded_offers
from alignment_ros.cli_options import split_ros_args
from alignment_ros.play_options import parse_args
from alignment_ros.progress import Progress
from alignment_ros.qos import STREAM
from alignment_ros.topics import msg_class

from .dds_teardown import say_once, shut_down
from .signals import stop_on_signals

NS = 1_000_000_000
CLOCK_QOS = QoSProfile(history=QoSHistoryPolicy.KEEP_LAST, depth=1,
                       reliability=QoSReliabilityPolicy.BEST_EFFORT,
                       durability=QoSDurabilityPolicy.VOLATILE)
"""rclcpp::ClockQoS, which rosbag2 publishes /clock with."""
log = logging.getLogger('player')


class PlayerError(RuntimeError):
    """An error that ends the player with status 1."""


def is_service_event(topic: str, type_name: str) -> bool:
    return topic.endswith('/_service_event') and type_name.endswith('_Event')


def allow_topic(topic: str, type_name: str, args: argparse.Namespace) -> bool:
    """rosbag2's topic filter: excludes first, then the include lists or the regex."""
    service = is_service_event(topic, type_name)
    if topic in (args.exclude_services if service else args.exclude_topics):
        return False
    if args.exclude_regex and re.fullmatch(args.exclude_regex, topic):
        return False
    include = args.services if service else args.topics
    if include or args.regex:
        if topic in include:
            return True
        if not args.regex:
            return False
        return re.fullmatch(args.regex, topic) is not None
    return True


def play_until(start_ns: int, args: argparse.Namespace) -> int:
    """rosbag2's end of playback: the later of start + duration and the until-stamp; -1: none,
    0: nothing (a duration of 0)."""
    if args.playback_duration >= 0 or args.play_until_ns >= 0:
        by_duration = 0 if args.playback_duration == 0 else start_ns + int(args.playback_duration * NS)
        return max(by_duration, args.play_until_ns)
    return -1


class PlayerClock:
    """rosbag2's time controller clock: ROS time running at ``rate`` x steady time from its last
    jump (with rate 0, the log time of the message being published)."""

    def __init__(self, start_ns: int, rate: float) -> None:
        self.rate = rate
        self.jump(start_ns)

    def jump(self, t_ns: int) -> None:
        self._ros0, self._wall0 = t_ns, time.monotonic()

    def now(self) -> int:
        if self.rate == 0:
            return self._ros0
        return self._ros0 + int((time.monotonic() - self._wall0) * self.rate * NS)

    def wall_time_of(self, t_ns: int) -> float:
        return self._wall0 + (t_ns - self._ros0) / NS / self.rate


def wait_for_subscribers(publishers: dict[str, Any], wanted: dict[str, int], timeout_s: float,
                         stop: dict[str, bool]) -> str | None:
    """Wait until each wanted topic has enough matched subscriptions; return an error or None."""
    deadline = time.monotonic() + timeout_s
    while True:
        short = {t: (publishers[t].get_subscription_count(), n) for t, n in wanted.items()
                 if publishers[t].get_subscription_count() < n}
        if not short:
            return None
        if stop['signal']:
            return 'interrupted while waiting for subscribers'
        if time.monotonic() >= deadline:
            detail = ', '.join(f'{t} has {have}/{n}' for t, (have, n) in short.items())
            return f'timed out after {timeout_s:g} s waiting for subscribers: {detail}'
        time.sleep(0.02)


class Playback:
    """One run of the player: publishers, the clock, the play loop, the counts."""

    def __init__(self, args: argparse.Namespace, reader: BagReader, node: Node,
                 overrides: dict[str, QoSProfile]) -> None:
        self.args, self.reader, self.node = args, reader, node
        bag_topics = reader.topics()
        first = next(iter(reader.messages()), None)
        self.start_ns = (first.t_ns if first else 0) + int(args.start_offset * NS)
        self.until_ns = play_until(self.start_ns, args)
        self.clock = PlayerClock(self.start_ns, args.rate)
        offers = recorded_offers(reader.path)
        self.pubs: dict[str, Any] = {}
        for topic, type_name in bag_topics.items():
            if not allow_topic(topic, type_name, args):
                continue
            try:
                cls = msg_class(type_name)
            except (ImportError, AttributeError, ValueError) as exc:
                log.warning("Ignoring a topic '%s', reason: %s.", topic, exc)
                continue
            qos = overrides.get(topic) or (STREAM if args.lossless else
                                           adapt_recorded(offers.get(topic, [])))
            self.pubs[topic] = node.create_publisher(cls, topic, qos)
        missing = [t for t in args.topics if t not in bag_topics]
        if missing:
            log.warning('topics not in the bag: %s', ', '.join(missing))
        self.counts = dict.fromkeys(self.pubs, 0)
        self.played = 0
        self.last_ns: int | None = None
        meta = reader.metadata()
        end_ns = meta.starting_time_ns + meta.duration_ns
        if self.until_ns > -1:
            end_ns = min(end_ns, self.until_ns)
        self.progress = Progress('play', max(0, end_ns - self.start_ns) / NS, self.start_ns / NS,
                                 quiet=args.quiet)
        self.clock_pub = None
        if args.clock > 0 or args.clock_topics or args.clock_topics_all:
            self.clock_pub = node.create_publisher(Clock, '/clock', CLOCK_QOS)

    def publish_clock(self) -> None:
        assert self.clock_pub is not None  # called only when /clock is played (--clock or --clock-topics*)
        self.clock_pub.publish(Clock(clock=Time(nanoseconds=self.clock.now()).to_msg()))

    def clock_ticks(self, done: threading.Event) -> None:
        """Publish /clock at ``--clock`` Hz (wall time) until ``done``."""
        period = 1.0 / self.args.clock
        while not done.wait(period):
            self.publish_clock()

    def play_once(self, stop: dict[str, bool]) -> None:
        """One pass over the bag from the start offset to the end (or the until-stamp)."""
        a = self.args
        if a.delay > 0 and _sleep(a.delay, stop):
            return
        self.clock.jump(self.start_ns)
        for topic, _type, t_ns, data in self.reader.messages(list(self.pubs)):
            if stop['signal']:
                return
            if t_ns < self.start_ns:
                continue
            if self.until_ns == 0 or (self.until_ns > -1 and t_ns > self.until_ns):
                return
            if a.rate > 0:
                if _sleep(self.clock.wall_time_of(t_ns) - time.monotonic(), stop):
                    return
            else:
                self.clock.jump(t_ns)
            if self.clock_pub is not None and (a.clock_topics_all or topic in a.clock_topics):
                self.publish_clock()
            self.pubs[topic].publish(data)
            self.counts[topic] += 1
            self.played += 1
            self.last_ns = t_ns
            if self.played % PROGRESS_EVERY == 0:
                self.progress.update(t_ns / NS, messages=self.played)

    def wait_acked(self) -> bool | None:
        """``--wait-for-all-acked``: None when not asked, else whether every message was acked.
        Not asked, the player still gives its reliable readers up to FINAL_ACK_S to take the last
        messages before it leaves (ros2 bag play may exit with them in flight)."""
        timeout_ms = self.args.wait_for_all_acked
        asked = timeout_ms >= 0
        if not asked:
            timeout_ms = int(FINAL_ACK_S * 1000)
        deadline = None if timeout_ms == 0 else time.monotonic() + timeout_ms / 1000
        acked = True
        for topic, pub in self.pubs.items():
            if pub.qos_profile.reliability != QoSReliabilityPolicy.RELIABLE:
                continue
            left = Duration(seconds=-1) if deadline is None else Duration(
                nanoseconds=int(max(0.0, deadline - time.monotonic()) * NS))
            if not pub.wait_for_all_acked(left):
                if asked:
                    log.error('Timed out while waiting for all published messages to be acknowledged '
                              'for topic %s', topic)
                acked = False
        return acked if asked else None


FINAL_ACK_S = 1.0
PROGRESS_EVERY = 50      # messages between progress updates (each is rate-limited too)


def _sleep(seconds: float, stop: dict[str, bool]) -> bool:
    """Sleep (in short steps, so that a signal ends it); return True if interrupted."""
    end = time.monotonic() + seconds
    while not stop['signal']:
        left = end - time.monotonic()
        if left <= 0:
            return False
        time.sleep(min(left, 0.05))
    return True


def play(args: argparse.Namespace, reader: BagReader, ros_argv: list[str],
         overrides: dict[str, QoSProfile],
         report: Callable[[dict[str, Any]], None] = lambda stats: None) -> dict[str, Any]:
    """Publish the bag; return the stats dict (PlayerError for what ends with status 1), given
    to `report` first, while the node still exists (its teardown is bounded: dds_teardown.py)."""
    rclpy.init(args=ros_argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = stop_on_signals()
    remaps = [a for rule in args.remap for a in ('--remap', rule)]
    node = Node('player', cli_args=['--ros-args', *remaps] if remaps else None,
                parameter_overrides=[Parameter('use_sim_time', value=False)])
    done = threading.Event()
    ticker: threading.Thread | None = None
    try:
        pb = Playback(args, reader, node, overrides)
        unplayed = [t for t, _ in args.wait_subscribers if t not in pb.pubs]
        if unplayed:
            raise PlayerError(f'--wait-subscribers topics not played: {", ".join(unplayed)}')
        err = wait_for_subscribers(pb.pubs, dict(args.wait_subscribers), args.wait_timeout, stop)
        if err:
            raise PlayerError(err)
        if args.clock > 0:
            pb.clock.jump(pb.start_ns)   # the clock starts with the playback, not before the wait
            ticker = threading.Thread(target=pb.clock_ticks, args=(done,), daemon=True)
            ticker.start()
        t_wall0 = time.monotonic()
        loops = 0
        while not stop['signal']:
            pb.play_once(stop)
            loops += 1
            if not args.loop:
                break
        wall = time.monotonic() - t_wall0
        pb.progress.close(None if pb.last_ns is None else pb.last_ns / NS, pb.played)
        done.set()
        acked = pb.wait_acked()
        stats = _stats(args, reader, pb, stop, loops, wall, acked)
        report(stats)
    except BaseException as exc:
        if isinstance(exc, (BagError, PlayerError)):     # its line before a teardown that might not end
            say_once(exc, f'player: {exc}')
        _stop_ticker(done, ticker)
        shut_down(node, status=1, signalled=stop['signal'])
        raise
    _stop_ticker(done, ticker)
    shut_down(node, status=0, signalled=stop['signal'])
    return stats


def _stop_ticker(done: threading.Event, ticker: threading.Thread | None) -> None:
    """The clock's ticks stopped."""
    done.set()
    if ticker is not None:
        ticker.join()


def _stats(args: argparse.Namespace, reader: BagReader, pb: Playback, stop: dict[str, bool], loops: int,
           wall: float, acked: bool | None) -> dict[str, Any]:
    """What the playback did (the --stats file)."""
    total = sum(pb.counts.values())
    return {
        'bag': str(args.bag_path),
        'topics': pb.counts,
        'total': total,
        'loops': loops,
        'truncated': reader.truncated,
        'acked': acked,
        'interrupted': stop['signal'],
        'wall_s': wall,
        'rate_msg_s': total / wall if wall > 0 else None,
    }


_LOG_LEVELS = {'debug': logging.DEBUG, 'info': logging.INFO, 'warn': logging.WARNING,
               'error': logging.ERROR, 'fatal': logging.CRITICAL}


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``player``."""
    own, ros = split_ros_args(sys.argv[1:] if argv is None else argv)
    args = parse_args(own)
    ros_argv = ['player', *ros]
    logging.basicConfig(level=_LOG_LEVELS[args.log_level],
                        format='player: %(levelname)s: %(message)s')
    overrides: dict[str, QoSProfile] = {}
    if args.qos_profile_overrides_path:
        try:
            overrides = load_overrides(args.qos_profile_overrides_path.name)
        except QoSOverrideError as exc:
            print(f'[ERROR] [ros2bag]: {exc}', file=sys.stderr)
            return 1
    try:
        reader = BagReader(args.bag_path)
        play(args, reader, ros_argv, overrides, lambda stats: _report(args, stats))
    except (BagError, PlayerError) as exc:
        say_once(exc, f'player: {exc}')
        return 1
    return 0


def _report(args: argparse.Namespace, stats: dict[str, Any]) -> None:
    """The stats file and the closing lines."""
    if args.stats:
        path = Path(args.stats)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(stats, indent=2) + '\n')
    per_topic = ', '.join(f'{t}: {n}' for t, n in stats['topics'].items())
    print(f'player: published {stats["total"]} messages in {stats["wall_s"]:.2f} s ({per_topic})',
          flush=True)
    if stats['truncated']:
        print(f'player: {args.bag_path} is truncated: played its readable prefix only',
              file=sys.stderr)
    if stats['acked'] is False:
        print('player: not every message was acknowledged before --wait-for-all-acked',
              file=sys.stderr)


if __name__ == '__main__':
    sys.exit(main())
