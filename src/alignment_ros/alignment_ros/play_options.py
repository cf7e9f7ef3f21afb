"""Command line of ``player`` / ``scripts/play.sh``: ``ros2 bag play``'s (Jazzy) options and
defaults, plus the few this project's replay needs (documented as extensions)."""
from __future__ import annotations

import argparse
import os

from alignment_ros.cli_options import (
    bag_positive_float,
    check_not_negative_float,
    check_not_negative_int,
    number,
)

LOSSLESS_ACK_TIMEOUT_MS = 30_000
"""With ``--lossless`` and no ``--wait-for-all-acked``: how long to wait for the final acks."""


def bag_path(text: str) -> str:
    """ros2bag's ``check_path_exists``."""
    if os.path.exists(text):
        return text
    raise argparse.ArgumentTypeError(f"Bag path '{text}' does not exist!")


def rate(text: str) -> float:
    """ros2bag's ``check_positive_float``, with 0 allowed (no pacing: an extension)."""
    value = number(text, float)
    if value < 0.0:
        raise argparse.ArgumentTypeError(f'{text} is not in the valid range (> 0.0)')
    return value


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


def build_parser() -> argparse.ArgumentParser:
    """The parser; help texts are ros2 bag play's."""
    p = argparse.ArgumentParser(prog='player', description='Play back ROS data from a bag.')
    p.add_argument('bag_path', type=bag_path, help='Bag to open')
    p.add_argument('-s', '--storage', default='', choices=['mcap'],
                   help='Storage implementation of bag. By default attempts to detect '
                        'automatically - use this argument to override.')
    p.add_argument('--read-ahead-queue-size', type=int, default=1000,
                   help='size of message queue rosbag tries to hold in memory to help '
                        'deterministic playback. Larger size will result in larger memory needs '
                        'but might prevent delay of message playback. (accepted; messages are '
                        'streamed from the MCAP index here)')
    p.add_argument('-r', '--rate', type=rate, default=1.0,
                   help='rate at which to play back messages. Valid range > 0.0. (Extension: 0 '
                        'plays as fast as the subscribers take the messages, no pacing.)')
    p.add_argument('--topics', type=str, default=[], metavar='topic', nargs='+',
                   help='Space-delimited list of topics to play.')
    p.add_argument('--services', type=str, default=[], metavar='service', nargs='+',
                   help='Space-delimited list of services to play.')
    p.add_argument('-e', '--regex', default='',
                   help='Play only topics and services matches with regular expression.')
    p.add_argument('-x', '--exclude-regex', default='',
                   help='regular expressions to exclude topics and services from replay.')
    p.add_argument('--exclude-topics', type=str, default=[], metavar='topic', nargs='+',
                   help='Space-delimited list of topics not to play.')
    p.add_argument('--exclude-services', type=str, default=[], metavar='service', nargs='+',
                   help='Space-delimited list of services not to play.')
    p.add_argument('--qos-profile-overrides-path', type=argparse.FileType('r'),
                   help='Path to a yaml file defining overrides of the QoS profile for specific '
                        'topics.')
    p.add_argument('-l', '--loop', action='store_true',
                   help='enables loop playback when playing a bagfile: it starts back at the '
                        'beginning on reaching the end and plays indefinitely.')
    p.add_argument('--remap', '-m', default='', nargs='+',
                   help='list of topics to be remapped: in the form '
                        '"old_topic1:=new_topic1 old_topic2:=new_topic2 etc." ')
    p.add_argument('--storage-config-file', type=argparse.FileType('r'),
                   help='Path to a yaml file defining storage specific configurations. See '
                        'storage plugin documentation for the format of this file. (accepted, '
                        'not used by the MCAP reader here)')
    clock = p.add_mutually_exclusive_group()
    clock.add_argument('--clock', type=bag_positive_float, nargs='?', const=40, default=0,
                       help='Publish to /clock at a specific frequency in Hz, to act as a ROS '
                            'Time Source. Value must be positive. Defaults to not publishing.If '
                            'specified, /clock topic in the bag file is excluded to publish.')
    clock.add_argument('--clock-topics', type=str, default=[], nargs='+',
                       help='List of topics separated by spaces that will trigger a /clock '
                            'update when a message is published on them')
    clock.add_argument('--clock-topics-all', default=False, action='store_true',
                       help='Publishes an update on /clock immediately before each replayed '
                            'message')
    p.add_argument('-d', '--delay', type=bag_positive_float, default=0.0,
                   help='Sleep duration before play (each loop), in seconds. Negative durations '
                        'invalid.')
    p.add_argument('--playback-duration', type=float, default=-1.0,
                   help='Playback duration, in seconds. Negative durations mark an infinite '
                        'playback. Default is %(default)d. When positive, the maximum effective '
                        'time between `playback-until-*` and this argument will determine when '
                        'playback stops.')
    until = p.add_mutually_exclusive_group()
    until.add_argument('--playback-until-sec', type=float, default=-1.,
                       help='Playback until timestamp, expressed in seconds since epoch. '
                            'Mutually exclusive argument with `--playback-until-nsec`. Use when '
                            'floating point to integer conversion error is not a concern. A '
                            'negative value disables this feature. Default is %(default)f. When '
                            'positive, the maximum effective time between `--playback-duration` '
                            'and this argument will determine when playback stops.')
    until.add_argument('--playback-until-nsec', type=int, default=-1,
                       help='Playback until timestamp, expressed in nanoseconds since epoch.  '
                            'Mutually exclusive argument with `--playback-until-sec`. Use when '
                            'floating point to integer conversion error matters for your use '
                            'case. A negative value disables this feature. Default is '
                            '%(default)s. When positive, the maximum effective time between '
                            '`--playback-duration` and this argument will determine when '
                            'playback stops.')
    p.add_argument('--disable-keyboard-controls', action='store_true',
                   help='disables keyboard controls for playback (there are none here)')
    p.add_argument('-p', '--start-paused', action='store_true', default=False,
                   help='Start the playback player in a paused state. (not supported here: '
                        'there is no keyboard control or service to resume)')
    p.add_argument('--start-offset', type=check_not_negative_float, default=0.0,
                   help='Start the playback player this many seconds into the bag file.')
    p.add_argument('--wait-for-all-acked', type=check_not_negative_int, default=-1,
                   metavar='TIMEOUT',
                   help='Wait until all published messages are acknowledged by all subscribers '
                        'or until the timeout elapses in millisecond before play is terminated. '
                        'Especially for the case of sending message with big size in a short '
                        'time. Negative timeout is invalid. 0 means wait forever until all '
                        'published messages are acknowledged by all subscribers. Note that this '
                        "option is valid only if the publisher's QOS profile is RELIABLE.")
    p.add_argument('--disable-loan-message', action='store_true', default=False,
                   help='Disable to publish as loaned message. (accepted; rclpy does not loan)')
    p.add_argument('--publish-service-requests', action='store_true', default=False,
                   help='Publish recorded service requests instead of recorded service events '
                        '(not supported here)')
    p.add_argument('--service-requests-source', default='service_introspection',
                   choices=['service_introspection', 'client_introspection'],
                   help='Determine the source of the service requests to be replayed. This '
                        'option only makes sense if the "--publish-service-requests" option is '
                        'set.')
    p.add_argument('--log-level', type=str, default='info',
                   choices=['debug', 'info', 'warn', 'error', 'fatal'], help='Logging level.')
    ext = p.add_argument_group('extensions of this project (not in ros2 bag play)')
    ext.add_argument('--lossless', action='store_true',
                     help='publish every topic RELIABLE + KEEP_ALL (a slow subscriber slows the '
                          'player instead of losing messages) and at the end wait for every '
                          'message to be acknowledged (--wait-for-all-acked, default '
                          f'{LOSSLESS_ACK_TIMEOUT_MS} ms)')
    ext.add_argument('--wait-subscribers', nargs='+', type=parse_wait, default=[],
                     metavar='TOPIC=N',
                     help='before playing, wait until TOPIC (as named in the bag) has N matched '
                          'subscriptions')
    ext.add_argument('--wait-timeout', type=float, default=30.0, metavar='S',
                     help='give up waiting for subscribers after S seconds (default 30): status 1')
    ext.add_argument('--stats', metavar='FILE', help='write the published counts as JSON')
    ext.add_argument('--quiet', action='store_true',
                     help='no progress line on stderr (bag time played, messages, rate, ETA)')
    return p


def expand(topic: str) -> str:
    """A topic name as the player node (namespace /) expands it."""
    return topic if topic.startswith('/') else '/' + topic


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Parse the command line (ROS arguments already removed); ros2's derived settings added:
    ``exclude_topics`` gets /clock with ``--clock``; ``play_until_ns`` from --playback-until-*."""
    p = build_parser()
    args = p.parse_args(argv)
    if args.start_paused:
        p.error('--start-paused is not supported here (no keyboard controls or ~/resume service)')
    if args.publish_service_requests:
        p.error('--publish-service-requests is not supported here')
    args.topics = [expand(t) for t in args.topics]
    args.exclude_topics = [expand(t) for t in args.exclude_topics]
    args.services = [expand(s) + '/_service_event' for s in args.services]
    args.exclude_services = [expand(s) + '/_service_event' for s in args.exclude_services]
    args.clock_topics = [expand(t) for t in args.clock_topics]
    if args.clock > 0:
        args.exclude_topics.append('/clock')
    if args.playback_until_sec and args.playback_until_sec >= 0.0:
        args.play_until_ns = int(args.playback_until_sec * 1_000_000_000)
    elif args.playback_until_nsec and args.playback_until_nsec >= 0:
        args.play_until_ns = args.playback_until_nsec
    else:
        args.play_until_ns = -1
    if args.lossless and args.wait_for_all_acked < 0:
        args.wait_for_all_acked = LOSSLESS_ACK_TIMEOUT_MS
    return args
