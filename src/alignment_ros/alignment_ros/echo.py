"""``echo TOPIC [TYPE]``: ``ros2 topic echo`` (Jazzy) for this testbed, where ros2cli is absent.

Same arguments, defaults, output and exit status as ``ros2 topic echo``: each message as a YAML
document and a ``---`` line (or one ``--csv`` row), arrays/bytes/strings truncated to
``--truncate-length`` (128) unless ``--full-length``; ``--field a.b``, ``--filter EXPR`` (on
``m``), ``--no-arr``, ``--no-str``, ``--flow-style``, ``--raw`` (the serialized bytes as
Python prints them), ``-i``, ``--once``, ``--timeout``; subscription QoS: the ``sensor_data``
preset (KEEP_LAST 5) made RELIABLE / TRANSIENT_LOCAL when every publisher offers it, or as the
``--qos-*`` options set it. Without TYPE the topic's type comes from the graph, looked up once
after ``--spin-time`` (0.5 s): an unknown topic fails then.

Exit status: 0 after ``--once``, ``--timeout`` (received or not) or a closed pipe; 1 when the
type cannot be determined or is invalid, or the field/filter is invalid; 2 for a usage error;
15 after SIGINT/SIGTERM (ros2: rclpy's shutdown on the signal ends its spin).

Extensions of this project: the topic contract (alignment_ros.topics) gives the type of the
graph's own topics, so echo can start before their publisher (which is then expected to offer
RELIABLE, VOLATILE); ``--count N`` stops after N messages; ``--csv-header`` prints column names
before the first CSV row.
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from typing import Any

import rclpy
import yaml
from rclpy.event_handler import SubscriptionEventCallbacks, UnsupportedEventTypeError
from rclpy.exceptions import InvalidTopicNameException
from rclpy.executors import SingleThreadedExecutor
from rclpy.expand_topic_name import expand_topic_name
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSDurabilityPolicy, QoSProfile, QoSReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rclpy.validate_full_topic_name import validate_full_topic_name

from alignment_ros.cli_options import (
    adapt_to_publishers,
    add_qos_arguments,
    positive_float,
    preset,
    qos_options_given,
    qos_profile_from_args,
    split_ros_args,
    unsigned_int,
)
from alignment_ros.dds_teardown import say_once, shut_down
from alignment_ros.echo_format import ECHO_TRUNCATE_LENGTH, to_csv_header, to_csv_row, to_yaml
from alignment_ros.topics import TOPIC_TYPES, msg_class

SPIN_TIME_S = 0.5
"""ros2cli's discovery wait before looking the topic up in the graph (``--spin-time``)."""

EXIT_SIGNAL = int(signal.SIGTERM)
"""ros2cli returns SIGTERM's number when a signal shut rclpy down during the spin."""


class EchoError(RuntimeError):
    """An error ros2 reports as its message on stderr with exit status 1."""


def build_parser() -> argparse.ArgumentParser:
    """``ros2 topic echo``'s options (help texts as ros2's), then this project's extensions."""
    p = argparse.ArgumentParser(prog='echo', description='Output messages from a topic.')
    p.add_argument('--spin-time', type=float, default=SPIN_TIME_S,
                   help='Spin time in seconds to wait for discovery (only applies when not '
                        'using an already running daemon)')
    p.add_argument('-s', '--use-sim-time', action='store_true', help='Enable ROS simulation time')
    p.add_argument('--no-daemon', action='store_true',
                   help='Do not spawn nor use an already running daemon (there is none here)')
    p.add_argument('topic_name', help="Name of the ROS topic to listen to (e.g. '/chatter')")
    p.add_argument('message_type', nargs='?',
                   help="Type of the ROS message (e.g. 'std_msgs/msg/String')")
    add_qos_arguments(p, 'subscribe', 'sensor_data')
    p.add_argument('--csv', action='store_true',
                   help='Output all recursive fields separated by commas (e.g. for plotting). '
                        'If --include-message-info is also passed, the following fields are '
                        'prepended: source_timestamp, received_timestamp, '
                        'publication_sequence_number, reception_sequence_number.')
    p.add_argument('--field', type=str, default=None,
                   help="Echo a selected field of a message. Use '.' to select sub-fields. For "
                        'example, to echo the position field of a nav_msgs/msg/Odometry message: '
                        "'ros2 topic echo /odom --field pose.pose.position'")
    p.add_argument('--full-length', '-f', action='store_true',
                   help='Output all elements for arrays, bytes, and string with a length > '
                        "'--truncate-length', by default they are truncated after "
                        "'--truncate-length' elements with '...''")
    p.add_argument('--truncate-length', '-l', type=unsigned_int, default=ECHO_TRUNCATE_LENGTH,
                   help='The length to truncate arrays, bytes, and string to (default: '
                        f'{ECHO_TRUNCATE_LENGTH})')
    p.add_argument('--no-arr', action='store_true', help="Don't print array fields of messages")
    p.add_argument('--no-str', action='store_true', help="Don't print string fields of messages")
    p.add_argument('--flow-style', action='store_true',
                   help='Print collections in the block style (not available with csv format)')
    p.add_argument('--no-lost-messages', action='store_true',
                   help="Don't report when a message is lost")
    p.add_argument('--raw', action='store_true', help='Echo the raw binary representation')
    p.add_argument('--filter', dest='filter_expr',
                   help='Python expression to filter messages that are printed. Expression can '
                        'use Python builtins as well as m (the message).')
    p.add_argument('--once', action='store_true',
                   help='Print the first message received and then exit.')
    p.add_argument('--timeout', metavar='N', type=positive_float, default=None,
                   help='Set a timeout in seconds for waiting')
    p.add_argument('--include-message-info', '-i', action='store_true',
                   help='Shows the associated message info.')
    ext = p.add_argument_group('extensions of this project (not in ros2 topic echo)')
    ext.add_argument('--count', type=int, metavar='N', help='exit after N printed messages')
    ext.add_argument('--csv-header', action='store_true',
                     help='with --csv: print column names before the first row')
    return p


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Parse the command line (ROS arguments already removed)."""
    p = build_parser()
    args = p.parse_args(argv)
    if args.count is not None and args.count < 1:
        p.error('--count must be >= 1')
    return args


def message_class(type_name: str) -> Any:
    """The message class of 'pkg/msg/Type' (or 'pkg/Type'), as rosidl_runtime_py resolves it."""
    parts = type_name.split('/')
    if len(parts) == 2:
        parts.insert(1, 'msg')
    try:
        cls = msg_class('/'.join(parts)) if len(parts) == 3 else None
    except (ImportError, AttributeError, ValueError):
        cls = None
    if cls is None or not hasattr(cls, 'SLOT_TYPES'):
        raise ValueError(type_name)
    return cls


def wait_for_publishers(node: Node, topic: str, spin_time: float) -> list[Any]:
    """Wait up to ``spin_time`` for the topic's publishers to be discovered; return their info."""
    deadline = time.monotonic() + spin_time
    while True:
        pubs = node.get_publishers_info_by_topic(topic)
        if pubs or time.monotonic() >= deadline:
            return pubs
        time.sleep(0.02)


def choose_qos(args: argparse.Namespace, offered: list[QoSProfile]) -> QoSProfile:
    """The subscription QoS ros2 would choose (notes on a mixed offer printed as ros2 does)."""
    if qos_options_given(args):
        return qos_profile_from_args(args)
    profile, notes = adapt_to_publishers(preset(args.qos_profile), offered)
    for note in notes:
        print(note)
    return profile


def graph_type(node: Node, topic: str) -> str | None:
    """The topic's type in the graph (hidden topics included), None if it is not there."""
    for name, types in node.get_topic_names_and_types():
        if name == topic:
            if len(types) > 1:
                raise EchoError(f"Cannot echo topic '{topic}', as it contains more than one "
                                f"type: [{', '.join(types)}]")
            return types[0]
    return None


class Printer:
    """The subscription callback: field, filter, format, print; counts and knows when to stop."""

    def __init__(self, args: argparse.Namespace, field: list[str] | None, filter_code: Any) -> None:
        self.args = args
        self.field = field
        self.filter_code = filter_code
        self.truncate = None if args.full_length else args.truncate_length
        self.limit = 1 if args.once else args.count
        self.printed = 0
        self.broken_pipe = False

    @property
    def done(self) -> bool:
        return self.broken_pipe or (self.limit is not None and self.printed >= self.limit)

    def __call__(self, msg: Any, info: Any) -> None:
        if self.done:
            return
        sub = msg
        field = self.field or []
        for name in field:
            try:
                sub = getattr(sub, name)
            except AttributeError as exc:
                raise EchoError(f"Invalid field '{'.'.join(field)}': {exc}") from None
        if self.filter_code is not None and not eval(self.filter_code, {}, {'m': sub}):  # noqa: S307
            return
        self.printed += 1
        self._write(self._text(sub, info))

    def _text(self, sub: Any, info: Any) -> str:
        a = self.args
        if not hasattr(sub, '__slots__'):  # --raw bytes, or a --field that is not a message
            head = (f'---Got new message, message info:---\n{info}\n---Message data:---\n'
                    if a.include_message_info else '')
            return f'{head}{sub}\n---\n'
        kw = {'truncate_length': self.truncate, 'no_arr': a.no_arr}
        if a.csv:
            row = to_csv_row(sub, no_str=a.no_str, **kw)
            if a.include_message_info:
                row = ','.join(str(x) for x in info.values()) + ',' + row
            if a.csv_header and self.printed == 1:
                row = to_csv_header(sub, **kw) + '\n' + row
            return row + '\n'
        head = yaml.dump(info) + '---\n' if a.include_message_info else ''
        return head + to_yaml(sub, no_str=a.no_str, flow_style=a.flow_style, **kw) + '---\n'

    def _write(self, text: str) -> None:
        try:
            sys.stdout.write(text)
            sys.stdout.flush()
        except BrokenPipeError:  # e.g. `echo ... | head`: stop quietly
            self.broken_pipe = True
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _message_lost(status: Any) -> None:
    print('A message was lost!!!\n\ttotal count change:'
          f'{status.total_count_change}\n\ttotal count: {status.total_count}', end='---\n',
          flush=True)


def _field_path(text: str | None) -> list[str] | None:
    if text is None:
        return None
    path = [p for p in text.split('.') if p]
    if not path:
        raise EchoError(f"Invalid field value '{text}'")
    return path


def _compile_filter(expr: str | None) -> Any:
    if not expr:
        return None
    try:
        return compile(expr, '<filter>', 'eval')
    except SyntaxError as exc:
        raise EchoError(f'Invalid filter expression {expr!r}: {exc}') from None


def run(args: argparse.Namespace, ros_argv: list[str]) -> int:
    """Subscribe and print until done; return the exit status (EchoError: status 1)."""
    printer = Printer(args, _field_path(args.field), _compile_filter(args.filter_expr))
    stop = {'signal': False, 'timeout': False}

    def on_signal(signum: int, frame: object) -> None:
        stop['signal'] = True

    rclpy.init(args=ros_argv, signal_handler_options=SignalHandlerOptions.NO)
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    node = Node(f'_echo_{os.getpid()}',
                parameter_overrides=[Parameter('use_sim_time', value=args.use_sim_time)])
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        try:
            topic = expand_topic_name(args.topic_name, node.get_name(), node.get_namespace())
            validate_full_topic_name(topic)
        except (ValueError, InvalidTopicNameException) as exc:
            raise EchoError(str(exc)) from None
        offered = [p.qos_profile for p in wait_for_publishers(node, topic, args.spin_time)]
        type_name = args.message_type
        if type_name is None:
            type_name = graph_type(node, topic) or TOPIC_TYPES.get(topic)
            if type_name is None:
                print(f'WARNING: topic [{args.topic_name}] does not appear to be published yet',
                      flush=True)
                raise EchoError('Could not determine the type for the passed topic')
            if not offered and topic in TOPIC_TYPES:  # contract topic, publisher not up yet
                offered = [QoSProfile(depth=1, reliability=QoSReliabilityPolicy.RELIABLE,
                                      durability=QoSDurabilityPolicy.VOLATILE)]
        try:
            cls = message_class(type_name)
        except ValueError:
            raise EchoError('The passed message type is invalid' if args.message_type
                            else f"The message type '{type_name}' is invalid") from None
        qos = choose_qos(args, offered)
        if args.timeout is not None:
            node.create_timer(args.timeout, lambda: stop.update(timeout=True))
        events = None if args.no_lost_messages else SubscriptionEventCallbacks(
            message_lost=_message_lost)
        # printer takes (message, MessageInfo): rclpy's Subscription accepts that form, but the hint of
        # Node.create_subscription in this rclpy names the one-argument form only
        try:
            node.create_subscription(cls, topic, printer, qos,  # type: ignore[arg-type]
                                     event_callbacks=events, raw=args.raw)
        except UnsupportedEventTypeError:
            node.create_subscription(cls, topic, printer, qos, raw=args.raw)  # type: ignore[arg-type]
        while not (printer.done or stop['signal'] or stop['timeout']):
            executor.spin_once(timeout_sec=0.1)
    except BaseException as exc:
        if isinstance(exc, EchoError):     # its line before a teardown that might not end
            say_once(exc, str(exc))
        shut_down(node, executor, status=1, signalled=stop['signal'])
        raise
    status = EXIT_SIGNAL if stop['signal'] and not printer.done else 0
    shut_down(node, executor, status=status, signalled=stop['signal'])
    return status


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``echo``."""
    own, ros = split_ros_args(sys.argv[1:] if argv is None else argv)
    args = parse_args(own)
    ros_argv = ['echo', *ros]
    try:
        return run(args, ros_argv)
    except EchoError as exc:
        say_once(exc, str(exc))
        return 1


if __name__ == '__main__':
    sys.exit(main())
