"""The recorder's command line: ``ros2 bag record``'s options (Jazzy) plus the graph's end rules.

Topic selection is rosbag2's (``TopicFilter``): ``-a/--all`` (every topic but hidden ones),
topics by name (positional or ``--topics``), by type (``--topic-types``) or ``-e/--regex``
(``re.search`` on the name), then ``--exclude-topics``, ``--exclude-topic-types`` and
``-x/--exclude-regex``; hidden topics (a name token starting with ``_``) only with
``--include-hidden-topics``, topics without a publisher only with
``--include-unpublished-topics``. Types come from the graph. Extension: a topic given as
``TOPIC=pkg/msg/Type``, or one of the project's topics (alignment_ros.topics), is subscribed at
once, before any publisher exists (the graph's nodes wait for the recorder's subscriptions).
"""
from __future__ import annotations

import argparse
import datetime
import re
from dataclasses import dataclass, field
from pathlib import Path

from alignment_ros.topics import TOPIC_TYPES, msg_class

SERVICE_EVENT_SUFFIX = '/_service_event'


def parse_topic(spec: str) -> tuple[str, str]:
    """'TOPIC' or 'TOPIC=pkg/msg/Type' -> (absolute topic, type or the project's type or '')."""
    topic, _, type_name = spec.partition('=')
    if not topic.startswith('/'):
        topic = '/' + topic
    return topic, type_name or TOPIC_TYPES.get(topic, '')


def is_hidden(topic: str) -> bool:
    """rclpy's rule: a name token starting with '_'."""
    return any(tok.startswith('_') for tok in topic.split('/') if tok)


@dataclass
class TopicFilter:
    """Which discovered topics to record (rosbag2_transport's TopicFilter, topics only)."""

    all_topics: bool = False
    topics: list[str] = field(default_factory=list)
    topic_types: list[str] = field(default_factory=list)
    regex: str = ''
    exclude_regex: str = ''
    exclude_topics: list[str] = field(default_factory=list)
    exclude_topic_types: list[str] = field(default_factory=list)
    include_hidden: bool = False
    include_unpublished: bool = False

    def take(self, topic: str, type_name: str) -> bool:
        """True if ``topic`` of ``type_name`` is selected (publishers are checked by the caller)."""
        if topic.endswith(SERVICE_EVENT_SUFFIX) and '/srv/' in type_name:
            return False  # services are not recorded here
        if not self.all_topics and topic not in self.topics and type_name not in self.topic_types:
            if not self.regex or not re.search(self.regex, topic):
                return False
        if type_name in self.exclude_topic_types or topic in self.exclude_topics:
            return False
        if self.exclude_regex and re.search(self.exclude_regex, topic):
            return False
        return self.include_hidden or not is_hidden(topic)

    def discovers(self) -> bool:
        """True if topics beyond an explicit list can be selected (discovery never ends)."""
        return bool(self.all_topics or self.topic_types or self.regex)


def _custom_data(items: list[str] | None) -> dict[str, str]:
    out = {}
    for kv in items or []:
        k, sep, v = kv.partition('=')
        if not sep:
            raise argparse.ArgumentTypeError(f'--custom-data expects KEY=VALUE, got {kv!r}')
        out[k] = v
    return out


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog='record', description='Record ROS topics to a rosbag2 MCAP '
                                'bag (the options of ros2 bag record, Jazzy, plus end rules).')
    p.add_argument('-o', '--output', '--out', dest='output', type=Path,
                   help='bag directory to create (default: rosbag2_YYYY_MM_DD-HH_MM_SS)')
    p.add_argument('-s', '--storage', default='mcap', choices=['mcap'], help='storage (mcap)')
    sel = p.add_mutually_exclusive_group()
    sel.add_argument('topics_positional', nargs='*', default=[], metavar='TOPIC[=TYPE]',
                     help='topics to record')
    sel.add_argument('--topics', nargs='+', default=[], metavar='TOPIC[=TYPE]',
                     help='topics to record')
    p.add_argument('--topic-types', nargs='+', default=[], metavar='TYPE',
                   help='record every topic of these types')
    p.add_argument('-a', '--all', action='store_true', help='record all topics (not hidden ones)')
    p.add_argument('--all-topics', action='store_true', help='record all topics')
    p.add_argument('-e', '--regex', default='', help='record topics whose name matches')
    p.add_argument('-x', '--exclude-regex', default='', help='exclude topics whose name matches')
    p.add_argument('--exclude-topic-types', nargs='+', default=[], metavar='TYPE')
    p.add_argument('--exclude-topics', nargs='+', default=[], metavar='TOPIC')
    p.add_argument('--include-unpublished-topics', action='store_true',
                   help='also record discovered topics without a publisher')
    p.add_argument('--include-hidden-topics', action='store_true')
    p.add_argument('--no-discovery', action='store_true',
                   help='only topics present at start-up are recorded')
    p.add_argument('-p', '--polling-interval', type=int, default=100, metavar='MS',
                   help='ms between graph queries for new topics (default 100)')
    p.add_argument('-b', '--max-bag-size', type=int, default=0, metavar='BYTES',
                   help='split the bag at this file size (default 0: no splitting)')
    p.add_argument('-d', '--max-bag-duration', type=int, default=0, metavar='S',
                   help='split the bag at this log-time span per file (default 0: none)')
    p.add_argument('--compression-mode', default='none', choices=['none', 'file', 'message'])
    p.add_argument('--compression-format', default='', choices=['zstd'])
    p.add_argument('--use-sim-time', action='store_true',
                   help='the recorder node runs on /clock (log time of unstamped messages)')
    p.add_argument('--node-name', default='rosbag2_recorder')
    p.add_argument('--custom-data', nargs='*', metavar='KEY=VALUE',
                   help='stored under custom_data in metadata.yaml')
    g = p.add_argument_group('end of recording (besides SIGINT/SIGTERM)')
    g.add_argument('--end-time', type=float, metavar='S', help='simulation time (s) to stop at')
    g.add_argument('--wait-topics', nargs='+', default=[], metavar='TOPIC',
                   help='with --end-time: topics that must also reach end-time before stopping')
    g.add_argument('--idle-timeout', type=float, default=0.0, metavar='S',
                   help='stop when nothing arrived for S wall seconds after the first message '
                        '(default 0: never)')
    g.add_argument('--drain', type=float, default=0.5, metavar='S',
                   help='after end-time, record until S wall seconds are quiet (default 0.5)')
    g.add_argument('--expect-counts', type=Path, metavar='FILE',
                   help="after end-time: wait for FILE ({topic: count}, the publishers' final "
                        'counts) and record until every topic has its count (instead of --drain)')
    g.add_argument('--expect-timeout', type=float, default=120.0, metavar='S',
                   help='with --expect-counts: give up S wall seconds after end-time (default 120)')
    g.add_argument('--stats', type=Path, metavar='FILE', help='write counts and end reason as JSON')
    g.add_argument('--executor', choices=('events', 'single'), default='events',
                   help='rclpy executor (default: events, the EventsExecutor)')
    g.add_argument('--quiet', action='store_true',
                   help='no progress line on stderr (simulation time, messages, rate)')
    g.add_argument('--progress-lines', action='store_true', help=argparse.SUPPRESS)  # launchers
    g.add_argument('--progress-topic', metavar='TOPIC',
                   help='publish the time every --wait-topics stream has reached (rosgraph_msgs/Clock, '
                        'best effort; never recorded), for a source that paces itself on the recorder')
    return p


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Parse and check the command line (ROS arguments already removed), as ros2 bag record
    does; ``args.typed`` are the topics subscribed at once, ``args.filter`` selects the rest."""
    p = build_parser()
    a = p.parse_args(argv)
    specs = [parse_topic(s) for s in (a.topics_positional or a.topics)]
    all_topics = a.all or a.all_topics
    if not (all_topics or specs or a.topic_types or a.regex):
        p.error('Need to specify at least one option out of --all, --all-topics, --topics, '
                '--topic-types or --regex')
    if (a.exclude_regex or a.exclude_topics or a.exclude_topic_types) and not (
            all_topics or a.topic_types or a.regex):
        p.error('--exclude-regex, --exclude-topics and --exclude-topic-types require either '
                '--all, --all-topics, --topic-types or --regex')
    a.output = a.output or Path(datetime.datetime.now().strftime('rosbag2_%Y_%m_%d-%H_%M_%S'))
    if a.output.exists():
        p.error(f"Output folder '{a.output}' already exists.")
    if a.use_sim_time and a.no_discovery:
        p.error('--use-sim-time and --no-discovery both set, but are incompatible settings.')
    if a.compression_format and a.compression_mode == 'none':
        p.error('Invalid choice: Cannot specify compression format without a compression mode.')
    if a.compression_mode != 'none' and not a.compression_format:
        p.error('--compression-mode needs --compression-format zstd')
    try:
        a.custom_data = _custom_data(a.custom_data)
    except argparse.ArgumentTypeError as exc:
        p.error(str(exc))
    for pattern in (a.regex, a.exclude_regex):
        try:
            re.compile(pattern)
        except re.error as exc:
            p.error(f'bad regular expression {pattern!r}: {exc}')
    a.typed = {t: ty for t, ty in specs if ty}
    for topic, type_name in a.typed.items():
        try:
            msg_class(type_name)
        except (ImportError, AttributeError, ValueError) as exc:
            p.error(f'{topic}: unusable message type {type_name!r}: {exc}')
    a.filter = TopicFilter(
        all_topics=all_topics, topics=[t for t, _ in specs], topic_types=a.topic_types,
        regex='' if all_topics else a.regex, exclude_regex=a.exclude_regex,
        exclude_topics=[parse_topic(t)[0] for t in a.exclude_topics],
        exclude_topic_types=a.exclude_topic_types, include_hidden=a.include_hidden_topics,
        include_unpublished=a.include_unpublished_topics)
    a.wait_topics = [parse_topic(t)[0] for t in a.wait_topics]
    missing = [t for t in a.wait_topics if not a.filter.discovers() and t not in a.filter.topics]
    if missing:
        p.error(f'--wait-topics not recorded: {", ".join(missing)}')
    if a.progress_topic is not None and not a.wait_topics:
        p.error('--progress-topic needs --wait-topics (the streams whose progress it publishes)')
    if a.progress_topic is not None:
        if a.progress_topic in a.filter.topics:
            p.error(f'{a.progress_topic}: the recorder cannot record its own --progress-topic')
        a.filter.exclude_topics.append(a.progress_topic)
    if a.expect_counts is not None and a.end_time is None:
        p.error('--expect-counts needs --end-time')
    return a
