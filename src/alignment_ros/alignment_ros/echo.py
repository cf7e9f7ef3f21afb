"""``echo TOPIC``: print a topic's messages like ``ros2 topic echo`` (ros2cli is not available).

Output is byte-for-byte ros2's: each message as a YAML document followed by a ``---`` line
(arrays, bytes and strings truncated to 128 elements unless ``--full-length``), or with
``--csv`` one comma-separated row per message (``--csv-header`` adds a column-name line first,
which ros2 does not print). Exit status: 0 after ``--once``/``--count``/Ctrl-C or when
``--timeout`` (a total run time) ends after at least one message; 1 if ``--timeout`` ends
with nothing received or the type cannot be determined.
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from typing import Any

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from alignment_ros.echo_format import ECHO_TRUNCATE_LENGTH, to_csv_header, to_csv_row, to_yaml
from alignment_ros.topics import TOPIC_TYPES, msg_class

DISCOVERY_WAIT_S = 5.0
"""How long to look for the topic's type in the graph when neither --type nor --timeout say."""


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Parse the command line (ROS arguments already removed)."""
    p = argparse.ArgumentParser(prog='echo', description=__doc__.splitlines()[0])
    p.add_argument('topic', help="topic name, e.g. '/aircraft/imu'")
    p.add_argument('--type', dest='type_name', metavar='pkg/msg/Type',
                   help='message type (default: from the topic contract, else from the graph)')
    p.add_argument('--once', action='store_true', help='print the first message and exit')
    p.add_argument('--count', type=int, metavar='N', help='exit after N messages')
    p.add_argument('--timeout', type=float, metavar='S',
                   help='stop after S wall seconds; exit 1 if nothing was received')
    p.add_argument('--csv', action='store_true', help='one comma-separated row per message')
    p.add_argument('--csv-header', action='store_true',
                   help='with --csv: print column names before the first row')
    p.add_argument('--full-length', '-f', action='store_true',
                   help='do not truncate arrays, bytes and strings')
    p.add_argument('--truncate-length', '-l', type=int, default=ECHO_TRUNCATE_LENGTH,
                   help=f'truncate arrays, bytes and strings to this length (default {ECHO_TRUNCATE_LENGTH})')
    args = p.parse_args(argv)
    if args.count is not None and args.count < 1:
        p.error('--count must be >= 1')
    if args.timeout is not None and args.timeout <= 0:
        p.error('--timeout must be > 0')
    if args.once:
        args.count = 1
    if not args.topic.startswith('/'):
        args.topic = '/' + args.topic
    if args.type_name and args.type_name.count('/') == 1:  # accept pkg/Type like ros2
        pkg, name = args.type_name.split('/')
        args.type_name = f'{pkg}/msg/{name}'
    return args


def discover_type(node: Node, topic: str, wait_s: float) -> str | None:
    """Look up the topic's type in the ROS graph, waiting up to ``wait_s`` seconds."""
    deadline = time.monotonic() + wait_s
    while True:
        for name, types in node.get_topic_names_and_types():
            if name == topic and types:
                if len(types) > 1:
                    raise RuntimeError(f'topic {topic} has more than one type: {", ".join(types)}')
                return types[0]
        if time.monotonic() >= deadline:
            return None
        time.sleep(0.1)


def choose_qos(node: Node, topic: str) -> QoSProfile:
    """KEEP_ALL, RELIABLE unless some publisher is best-effort, TRANSIENT_LOCAL if all are."""
    pubs = node.get_publishers_info_by_topic(topic)
    reliable = all(p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in pubs)
    latched = bool(pubs) and all(
        p.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in pubs)
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )


class _Printer:
    """Subscription callback: formats and prints, counts, remembers when to stop."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.truncate = None if args.full_length else args.truncate_length
        self.received = 0
        self.broken_pipe = False

    @property
    def done(self) -> bool:
        return self.broken_pipe or (self.args.count is not None and self.received >= self.args.count)

    def __call__(self, msg: Any) -> None:
        if self.done:
            return
        if self.args.csv:
            text = to_csv_row(msg, truncate_length=self.truncate) + '\n'
            if self.args.csv_header and self.received == 0:
                text = to_csv_header(msg, truncate_length=self.truncate) + '\n' + text
        else:
            text = to_yaml(msg, truncate_length=self.truncate) + '---\n'
        self.received += 1
        try:
            sys.stdout.write(text)
            sys.stdout.flush()
        except BrokenPipeError:  # e.g. `echo ... | head`: stop quietly
            self.broken_pipe = True
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``echo``."""
    raw_argv = sys.argv if argv is None else ['echo', *argv]
    args = parse_args(remove_ros_args(raw_argv)[1:])
    start = time.monotonic()
    stop = {'signal': False}

    def on_signal(signum: int, frame: object) -> None:
        stop['signal'] = True

    rclpy.init(args=raw_argv, signal_handler_options=SignalHandlerOptions.NO)
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    node = Node(f'_echo_{os.getpid()}',
                parameter_overrides=[Parameter('use_sim_time', value=False)])
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    printer = _Printer(args)
    code = 0
    try:
        type_name = args.type_name or TOPIC_TYPES.get(args.topic)
        if type_name is None:
            wait = args.timeout if args.timeout is not None else DISCOVERY_WAIT_S
            type_name = discover_type(node, args.topic, wait)
            if type_name is None:
                print(f'echo: could not determine the type of {args.topic} (not in the topic '
                      f'contract and not seen in the graph within {wait:g} s); pass --type',
                      file=sys.stderr)
                return 1
        try:
            cls = msg_class(type_name)
        except (ImportError, AttributeError, ValueError) as exc:
            print(f'echo: invalid message type {type_name!r}: {exc}', file=sys.stderr)
            return 1
        node.create_subscription(cls, args.topic, printer, choose_qos(node, args.topic))
        deadline = None if args.timeout is None else start + args.timeout
        while not (printer.done or stop['signal']):
            if deadline is not None and time.monotonic() >= deadline:
                break
            executor.spin_once(timeout_sec=0.1)
        if printer.broken_pipe:
            code = 0
        elif deadline is not None and printer.received == 0 and not stop['signal']:
            print(f'echo: no message received on {args.topic} within {args.timeout:g} s',
                  file=sys.stderr)
            code = 1
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return code


if __name__ == '__main__':
    sys.exit(main())
