"""``player BAG``: publish a rosbag2 MCAP bag's messages (rosbag2 is not available here).

Messages are published as stored (serialized CDR bytes, no deserialisation) in log-time order
with the STREAM QoS (RELIABLE + KEEP_ALL), ``/clock`` included when the bag has it. Before the
first message the player waits until each ``--wait-subscribers TOPIC=N`` topic has N matched
subscriptions; at the end it waits until every subscriber acknowledged every message.
``--rate R`` paces by simulation (log) time, R times real time; ``--rate 0`` (default) plays as
fast as the subscribers take it (KEEP_ALL: a slow subscriber slows the player, nothing is lost).

A truncated bag plays its readable prefix: a warning goes to stderr, the exit status stays 0
and the stats say ``"truncated": true``. Exit status 1: not a bag, an unknown topic, or
subscribers not matched in time.
"""
from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path
from typing import Any

import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from alignment_ros.bag import BagError, BagReader
from alignment_ros.node_util import stop_on_signals
from alignment_ros.qos import STREAM
from alignment_ros.topics import msg_class

NS = 1_000_000_000


def parse_wait(spec: str) -> tuple[str, int]:
    """'TOPIC=N' (or 'TOPIC', meaning N=1) -> (topic, N)."""
    topic, _, n = spec.partition('=')
    if not topic.startswith('/'):
        topic = '/' + topic
    try:
        count = int(n) if n else 1
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected TOPIC=N, got {spec!r}') from None
    if count < 0:
        raise argparse.ArgumentTypeError(f'N must be >= 0 in {spec!r}')
    return topic, count


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Parse the command line (ROS arguments already removed)."""
    p = argparse.ArgumentParser(prog='player', description=__doc__.splitlines()[0])
    p.add_argument('bag', type=Path, help='bag directory (or its .mcap file)')
    p.add_argument('--topics', nargs='+', metavar='TOPIC', help='play only these topics')
    p.add_argument('--rate', type=float, default=0.0,
                   help='R x real time by simulation time; 0 = as fast as possible (default)')
    p.add_argument('--wait-subscribers', nargs='+', type=parse_wait, default=[],
                   metavar='TOPIC=N', help='wait until TOPIC has N matched subscriptions')
    p.add_argument('--wait-timeout', type=float, default=30.0, metavar='S',
                   help='give up waiting for subscribers after S seconds (default 30)')
    p.add_argument('--ack-timeout', type=float, default=30.0, metavar='S',
                   help='at the end, wait up to S seconds for all messages to be acknowledged')
    p.add_argument('--stats', type=Path, metavar='FILE', help='write counts as JSON')
    args = p.parse_args(argv)
    if args.rate < 0:
        p.error('--rate must be >= 0')
    if args.topics:
        args.topics = [t if t.startswith('/') else '/' + t for t in args.topics]
    return args


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


def play(args: argparse.Namespace, reader: BagReader, ros_argv: list[str]) -> dict[str, Any]:
    """Publish the bag; return the stats dict (raises SystemExit-worthy errors as RuntimeError)."""
    bag_topics = reader.topics()
    topics = args.topics or list(bag_topics)
    unknown = [t for t in topics if t not in bag_topics]
    unknown += [t for t, _ in args.wait_subscribers if t not in topics]
    if unknown:
        raise RuntimeError(f'topics not in the bag (or not played): {", ".join(unknown)}')
    rclpy.init(args=ros_argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = stop_on_signals()
    node = Node('player', parameter_overrides=[Parameter('use_sim_time', value=False)])
    counts = dict.fromkeys(topics, 0)
    acked = True
    try:
        pubs = {}
        for t in topics:
            try:
                cls = msg_class(bag_topics[t])
            except (ImportError, AttributeError, ValueError) as exc:
                raise RuntimeError(f'{t}: cannot load message type {bag_topics[t]!r}: {exc}') from exc
            pubs[t] = node.create_publisher(cls, t, STREAM)
        err = wait_for_subscribers(pubs, dict(args.wait_subscribers), args.wait_timeout, stop)
        if err:
            raise RuntimeError(err)
        t_wall0 = time.monotonic()
        t_sim0: int | None = None
        for topic, _type, t_ns, data in reader.messages(topics):
            if stop['signal']:
                break
            if args.rate > 0:
                if t_sim0 is None:
                    t_sim0 = t_ns
                delay = t_wall0 + (t_ns - t_sim0) / NS / args.rate - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            pubs[topic].publish(data)
            counts[topic] += 1
        wall = time.monotonic() - t_wall0
        ack_deadline = time.monotonic() + args.ack_timeout
        for pub in pubs.values():
            left = max(0.0, ack_deadline - time.monotonic())
            acked = pub.wait_for_all_acked(Duration(nanoseconds=int(left * NS))) and acked
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    total = sum(counts.values())
    return {
        'bag': str(args.bag),
        'topics': counts,
        'total': total,
        'truncated': reader.truncated,
        'acked': acked,
        'interrupted': stop['signal'],
        'wall_s': wall,
        'rate_msg_s': total / wall if wall > 0 else None,
    }


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``player``."""
    logging.basicConfig(level=logging.WARNING, format='player: %(levelname)s: %(message)s')
    raw_argv = sys.argv if argv is None else ['player', *argv]
    args = parse_args(remove_ros_args(raw_argv)[1:])
    try:
        reader = BagReader(args.bag)
        stats = play(args, reader, raw_argv)
    except (BagError, RuntimeError) as exc:
        print(f'player: {exc}', file=sys.stderr)
        return 1
    if args.stats:
        args.stats.parent.mkdir(parents=True, exist_ok=True)
        args.stats.write_text(json.dumps(stats, indent=2) + '\n')
    per_topic = ', '.join(f'{t}: {n}' for t, n in stats['topics'].items())
    print(f'player: published {stats["total"]} messages in {stats["wall_s"]:.2f} s ({per_topic})',
          flush=True)
    if stats['truncated']:
        print(f'player: {args.bag} is truncated: played its readable prefix only', file=sys.stderr)
    if not stats['acked']:
        print('player: not every message was acknowledged before --ack-timeout', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
