"""``bag_info BAG``: print what ``ros2 bag info`` (Jazzy) prints about a rosbag2 MCAP bag.

The text is rosbag2_py's ``format_bag_meta_data``: files, bag size (KiB/MiB with one decimal),
storage id, ROS distro, duration, start and end (local time, like rosbag2), messages, one line
per topic, then services (service event topics). The metadata comes from metadata.yaml, or,
for a lone ``.mcap`` file or a directory without one, from the MCAP files' summaries and
``rosbag2`` records (see :meth:`alignment_ros.bag.BagReader.metadata`).
"""
from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

from alignment_ros.bag import BagError, BagReader
from alignment_ros.bag_metadata import BagMetadata, TopicInfo

INDENT = 19  # the longest field name ("Topic information:") plus one space
NS = 1_000_000_000


def is_service_event(topic: TopicInfo) -> bool:
    """A service event topic (``/srv/..._Event`` on ``.../_service_event``), as rosbag2 tells."""
    return ('/srv/' in topic.type and topic.type.endswith('_Event')
            and topic.name.endswith('/_service_event'))


def format_duration_s(ns: int) -> str:
    """Seconds with nine decimals, e.g. '12.000000000' (rosbag2's time_in_sec)."""
    sec = int(ns / NS)  # toward zero, as std::chrono::duration_cast
    return f'{sec}.{ns - sec * NS:09d}'


def format_time_point(ns: int) -> str:
    """'Jan  1 1970 00:00:01.000000000 (1.000000000)', local time."""
    sec = int(ns / NS)
    t = time.localtime(sec)
    return (time.strftime('%b %e %Y %H:%M:%S', t) + f'.{ns - sec * NS:09d}'
            + f' ({format_duration_s(ns)})')


def format_file_size(size: int) -> str:
    """'512 B', '1.5 KiB', '12.0 MiB' (binary units, one decimal above bytes)."""
    value = float(size)
    units = ('B', 'KiB', 'MiB', 'GiB', 'TiB')
    i = 0
    while value >= 1024 and i < 4:
        value /= 1024
        i += 1
    return f'{value:.0f} {units[i]}' if i == 0 else f'{value:.1f} {units[i]}'


def _lines(items: list[str], indent: int) -> str:
    if not items:
        return '\n'
    return items[0] + '\n' + ''.join(' ' * indent + s + '\n' for s in items[1:])


def format_bag_metadata(meta: BagMetadata) -> str:
    """The text ``ros2 bag info`` prints (without print's final newline)."""
    topics = [t for t in meta.topics if not is_service_event(t)]
    services = [t for t in meta.topics if is_service_event(t)]
    service_events = sum(t.message_count for t in services)
    out = '\n'
    out += 'Files:             ' + _lines(meta.relative_file_paths, INDENT)
    out += f'Bag size:          {format_file_size(meta.bag_size)}\n'
    out += f'Storage id:        {meta.storage_identifier}\n'
    out += f'ROS Distro:        {meta.ros_distro or "unknown"}\n'
    out += f'Duration:          {format_duration_s(meta.duration_ns)}s\n'
    out += f'Start:             {format_time_point(meta.starting_time_ns)}\n'
    out += f'End:               {format_time_point(meta.starting_time_ns + meta.duration_ns)}\n'
    out += f'Messages:          {meta.message_count - service_events}\n'
    out += 'Topic information: ' + _lines(
        [f'Topic: {t.name} | Type: {t.type} | Count: {t.message_count} | '
         f'Serialization Format: {t.serialization_format}' for t in topics], INDENT)
    out += f'Service:           {len(services)}\n'
    out += 'Service information: '
    if services:
        out += _lines([
            f'Service: {t.name[:-len("/_service_event")]} | '
            f'Type: {t.type[:-len("_Event")]} | Event Count: {t.message_count} | '
            f'Serialization Format: {t.serialization_format}' for t in services], INDENT + 2)
    return out


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``bag_info`` (scripts/bag_info.sh)."""
    p = argparse.ArgumentParser(prog='bag_info', description=__doc__.splitlines()[0])
    p.add_argument('bag_path', type=Path, help='bag directory or .mcap file')
    p.add_argument('-s', '--storage', default='mcap', choices=['mcap'],
                   help='storage identifier (only mcap)')
    p.add_argument('-t', '--topic-name', action='store_true', help='only display topic names')
    args = p.parse_args(argv)
    logging.basicConfig(format='[WARN] %(message)s', level=logging.WARNING, stream=sys.stderr)
    try:
        meta = BagReader(args.bag_path).metadata()
    except BagError as exc:
        print(f'bag_info: {exc}', file=sys.stderr)
        return 1
    if args.topic_name:
        for t in meta.topics:
            if not is_service_event(t):
                print(t.name)
    else:
        print(format_bag_metadata(meta))
    return 0


if __name__ == '__main__':
    sys.exit(main())
