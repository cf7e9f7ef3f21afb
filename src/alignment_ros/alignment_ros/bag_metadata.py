"""What a rosbag2 bag says about itself: ``metadata.yaml`` (version 9, as rosbag2 Jazzy writes
it with yaml-cpp) and the QoS profile strings of MCAP channels. No rclpy import.

:func:`to_yaml` emits yaml-cpp's block style (sequences indented under their key, ``""`` for
empty strings, ``~`` for an empty custom_data, no final newline); :func:`from_yaml` reads any
rosbag2 version (QoS profiles as a YAML string before version 9, as a list from 9).
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from typing import Any

import yaml

SAFE_LOADER = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)
"""yaml.safe_load's loader, through libyaml when PyYAML has it: a run's metadata (its QoS
profiles are YAML inside the YAML) parsed in 0.27 s of pure Python before."""

VERSION = 9
ROS_DISTRO = os.environ.get('ROS_DISTRO') or 'jazzy'  # the rclpy wheels are Jazzy's
INFINITE = {'sec': 9223372036, 'nsec': 854775807}  # RMW_DURATION_INFINITE, as rosbag2 writes it

STREAM_QOS: dict[str, Any] = {
    'history': 'keep_all', 'depth': 0, 'reliability': 'reliable', 'durability': 'volatile',
    'deadline': dict(INFINITE), 'lifespan': dict(INFINITE), 'liveliness': 'automatic',
    'liveliness_lease_duration': dict(INFINITE), 'avoid_ros_namespace_conventions': False,
}
"""alignment_ros.qos.STREAM as an offered QoS profile (for bags written without a graph)."""

# QoS policies as integers (rosbag2 metadata before version 9): rmw's enum order
_POLICY_NAMES = {
    'history': ('system_default', 'keep_last', 'keep_all', 'unknown'),
    'reliability': ('system_default', 'reliable', 'best_effort', 'unknown', 'best_available'),
    'durability': ('system_default', 'transient_local', 'volatile', 'unknown', 'best_available'),
    'liveliness': ('system_default', 'automatic', 'manual_by_node', 'manual_by_topic', 'unknown',
                   'best_available'),
}


class BagError(Exception):
    """A path that is not a readable rosbag2 MCAP bag, or a misuse of the bag writer."""


@dataclass
class TopicInfo:
    """One entry of ``topics_with_message_count``."""

    name: str
    type: str
    serialization_format: str = 'cdr'
    offered_qos_profiles: list[dict[str, Any]] = field(default_factory=list)
    type_description_hash: str = ''
    message_count: int = 0


@dataclass
class FileInfo:
    """One entry of ``files``: a bag file's first log time, span and message count."""

    path: str
    starting_time_ns: int
    duration_ns: int = 0
    message_count: int = 0


@dataclass
class BagMetadata:
    """``rosbag2_bagfile_information``; ``bag_size`` (bytes) is not stored, readers measure it."""

    version: int = VERSION
    storage_identifier: str = 'mcap'
    duration_ns: int = 0
    starting_time_ns: int = 0
    message_count: int = 0
    topics: list[TopicInfo] = field(default_factory=list)
    compression_format: str = ''
    compression_mode: str = ''
    relative_file_paths: list[str] = field(default_factory=list)
    files: list[FileInfo] = field(default_factory=list)
    custom_data: dict[str, str] | None = None
    ros_distro: str = ROS_DISTRO
    bag_size: int = 0


# --- yaml-cpp style emitter -----------------------------------------------------------------

_PLAIN = re.compile(r'^[A-Za-z0-9_./(][A-Za-z0-9_./()+\- ]*$')
_YAML_WORDS = {'~', 'null', 'Null', 'NULL', 'y', 'Y', 'yes', 'Yes', 'YES', 'n', 'N', 'no', 'No',
               'NO', 'true', 'True', 'TRUE', 'false', 'False', 'FALSE', 'on', 'On', 'ON', 'off',
               'Off', 'OFF'}


def _scalar(v: Any) -> str:
    if isinstance(v, bool):
        return 'true' if v else 'false'
    if isinstance(v, int):
        return str(v)
    s = str(v)
    if _PLAIN.match(s) and s not in _YAML_WORDS and not s.endswith(' '):
        return s
    return '"' + s.replace('\\', '\\\\').replace('"', '\\"').replace('\n', '\\n') + '"'


def _block(v: Any, indent: int) -> list[str]:
    """Lines of a map or sequence at column ``indent`` (yaml-cpp layout)."""
    pad = ' ' * indent
    lines: list[str] = []
    if isinstance(v, dict):
        for k, x in v.items():
            if isinstance(x, (dict, list)) and x:
                lines.append(f'{pad}{k}:')
                lines += _block(x, indent + 2)
            elif isinstance(x, (dict, list)):
                lines += [f'{pad}{k}:', f'{pad}  {"[]" if isinstance(x, list) else "{}"}']
            else:
                lines.append(f'{pad}{k}: {"~" if x is None else _scalar(x)}')
    else:
        for x in v:
            if isinstance(x, (dict, list)) and x:
                sub = _block(x, indent + 2)
                lines.append(f'{pad}- {sub[0].lstrip()}')
                lines += sub[1:]
            else:
                lines.append(f'{pad}- {"~" if x is None else _scalar(x)}')
    return lines


def dump_yaml(v: dict | list) -> str:
    """YAML text as yaml-cpp's ``YAML::Dump`` writes it (no final newline; ``[]`` if empty)."""
    return '\n'.join(_block(v, 0)) if v else '[]'


def qos_string(profiles: list[dict[str, Any]]) -> str:
    """The ``offered_qos_profiles`` value of an MCAP channel's metadata (rosbag2 version 9)."""
    return dump_yaml(profiles)


def _tree(meta: BagMetadata) -> dict[str, Any]:
    return {
        'version': meta.version,
        'storage_identifier': meta.storage_identifier,
        'duration': {'nanoseconds': meta.duration_ns},
        'starting_time': {'nanoseconds_since_epoch': meta.starting_time_ns},
        'message_count': meta.message_count,
        'topics_with_message_count': [{
            'topic_metadata': {
                'name': t.name, 'type': t.type, 'serialization_format': t.serialization_format,
                'offered_qos_profiles': t.offered_qos_profiles,
                'type_description_hash': t.type_description_hash,
            },
            'message_count': t.message_count} for t in meta.topics],
        'compression_format': meta.compression_format,
        'compression_mode': meta.compression_mode,
        'relative_file_paths': meta.relative_file_paths,
        'files': [{'path': f.path, 'starting_time': {'nanoseconds_since_epoch': f.starting_time_ns},
                   'duration': {'nanoseconds': f.duration_ns}, 'message_count': f.message_count}
                  for f in meta.files],
        'custom_data': meta.custom_data or None,
        'ros_distro': meta.ros_distro,
    }


def to_yaml(meta: BagMetadata, *, wrapped: bool = True) -> str:
    """metadata.yaml text (``wrapped``), or the ``serialized_metadata`` of the MCAP ``rosbag2``
    metadata record (the same map without the ``rosbag2_bagfile_information`` key)."""
    tree = _tree(meta)
    return dump_yaml({'rosbag2_bagfile_information': tree} if wrapped else tree)


# --- reading --------------------------------------------------------------------------------

def _ns(node: Any, key: str) -> int:
    return int(node[key]) if isinstance(node, dict) else 0


def parse_qos(value: Any) -> list[dict[str, Any]]:
    """Offered QoS profiles from metadata or channel metadata (string or list, any version),
    with the policies as names (version 9 form)."""
    if isinstance(value, str):
        value = yaml.load(value, Loader=SAFE_LOADER) if value.strip() else []
    out = []
    for p in value or []:
        q = dict(p)
        for k, names in _POLICY_NAMES.items():
            if isinstance(q.get(k), int) and not isinstance(q.get(k), bool):
                q[k] = names[q[k]] if 0 <= q[k] < len(names) else 'unknown'
        out.append(q)
    return out


def from_dict(info: dict[str, Any]) -> BagMetadata:
    """BagMetadata from a parsed ``rosbag2_bagfile_information`` map (any rosbag2 version)."""
    try:
        version = int(info['version'])
        topics = []
        for t in info.get('topics_with_message_count') or []:
            md = t['topic_metadata']
            topics.append(TopicInfo(
                name=md['name'], type=md['type'],
                serialization_format=md.get('serialization_format', ''),
                offered_qos_profiles=parse_qos(md.get('offered_qos_profiles')),
                type_description_hash=md.get('type_description_hash') or '',
                message_count=int(t.get('message_count', 0))))
        files = [FileInfo(f['path'], _ns(f.get('starting_time'), 'nanoseconds_since_epoch'),
                          _ns(f.get('duration'), 'nanoseconds'), int(f.get('message_count', 0)))
                 for f in info.get('files') or []]
        return BagMetadata(
            version=version, storage_identifier=info['storage_identifier'],
            duration_ns=_ns(info.get('duration'), 'nanoseconds'),
            starting_time_ns=_ns(info.get('starting_time'), 'nanoseconds_since_epoch'),
            message_count=int(info.get('message_count', 0)), topics=topics,
            compression_format=info.get('compression_format') or '',
            compression_mode=info.get('compression_mode') or '',
            relative_file_paths=list(info.get('relative_file_paths') or []), files=files,
            custom_data={str(k): str(v) for k, v in (info.get('custom_data') or {}).items()},
            ros_distro=info.get('ros_distro') or '')
    except (KeyError, TypeError, ValueError, yaml.YAMLError) as exc:
        raise BagError(f'unreadable rosbag2 metadata: {type(exc).__name__}: {exc}') from exc


def from_yaml(text: str) -> BagMetadata:
    """Parse metadata.yaml text (``rosbag2_bagfile_information`` at the top) or a ``rosbag2``
    MCAP metadata record's ``serialized_metadata`` (the map itself)."""
    try:
        doc = yaml.load(text, Loader=SAFE_LOADER)
    except yaml.YAMLError as exc:
        raise BagError(f'unreadable rosbag2 metadata: {exc}') from exc
    if not isinstance(doc, dict):
        raise BagError('unreadable rosbag2 metadata: not a map')
    return from_dict(doc.get('rosbag2_bagfile_information', doc))
