"""Bag QoS: what the recorder subscribes with and stores of the publishers' offers, and what
``ros2 bag play`` offers for each topic: recorded offer, or ``--qos-profile-overrides-path``.

rosbag2 (Jazzy) offers what the recorded publishers offered (metadata.yaml's
``offered_qos_profiles``) with the history reset to KEEP_LAST 10; when the recorded publishers
disagree, or nothing was recorded, it offers its default (KEEP_LAST 10, RELIABLE, VOLATILE). An
overrides file maps topic names to profiles written with rosbag2's keys (history, depth,
reliability, durability, deadline/lifespan/liveliness_lease_duration as ``{sec, nsec}``,
liveliness, avoid_ros_namespace_conventions) and takes precedence.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from rclpy.duration import Duration
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    InvalidQoSProfileException,
    QoSDurabilityPolicy,
    QoSHistoryPolicy,
    QoSLivelinessPolicy,
    QoSProfile,
    QoSReliabilityPolicy,
    ReliabilityPolicy,
)

NS = 1_000_000_000
DEFAULT_DEPTH = 10
"""rmw_qos_profile_default's depth: rosbag2's default offer and the depth of adapted offers."""

_POLICIES = {
    'history': QoSHistoryPolicy,
    'reliability': QoSReliabilityPolicy,
    'durability': QoSDurabilityPolicy,
    'liveliness': QoSLivelinessPolicy,
}
_DURATION_KEYS = ('deadline', 'lifespan', 'liveliness_lease_duration')
_VALUE_KEYS = ('depth', 'avoid_ros_namespace_conventions')
_INFINITE_S = 9223372036  # rmw's "infinite" duration is {9223372036 s, 854775807 ns}
_SAME_KEYS = ('reliability', 'durability', 'deadline', 'liveliness', 'liveliness_lease_duration',
              'avoid_ros_namespace_conventions')
"""What rosbag2 compares to call recorded offers the same (history and lifespan are local)."""


class QoSOverrideError(ValueError):
    """An unusable ``--qos-profile-overrides-path`` file (ros2 prints it as an ERROR, status 1)."""


def rosbag2_default() -> QoSProfile:
    """rosbag2's default publisher offer."""
    return QoSProfile(history=QoSHistoryPolicy.KEEP_LAST, depth=DEFAULT_DEPTH,
                      reliability=QoSReliabilityPolicy.RELIABLE,
                      durability=QoSDurabilityPolicy.VOLATILE)


def _duration(value: Any, *, recorded: bool) -> Duration:
    if not value:
        return Duration()
    try:
        sec, nsec = value['sec'], value['nsec']
    except (KeyError, TypeError):
        raise QoSOverrideError(
            'Time overrides must include both seconds (sec) and nanoseconds (nsec).') from None
    if recorded and sec >= _INFINITE_S:
        return Duration()  # "infinite" is the DDS default: leave it unspecified
    d = Duration(seconds=sec, nanoseconds=nsec)
    if d < Duration():
        raise QoSOverrideError('Time duration may not be a negative value.')
    return d


def _policy(key: str, value: Any) -> Any:
    enum = _POLICIES[key]
    if isinstance(value, int):
        return enum(value)
    try:
        return enum.get_from_short_key(str(value))
    except KeyError:
        raise QoSOverrideError(f'Unknown {key} policy `{value}`.') from None


def profile_from_dict(entry: dict[str, Any], *, recorded: bool = False) -> QoSProfile:
    """A QoSProfile from a dict with rosbag2's keys (QoSOverrideError for a bad key or value)."""
    kw: dict[str, Any] = {}
    for key, value in entry.items():
        if key in _DURATION_KEYS:
            kw[key] = _duration(value, recorded=recorded)
        elif key in _POLICIES:
            kw[key] = _policy(key, value)
        elif key in _VALUE_KEYS:
            if value < 0:
                raise QoSOverrideError(f'`{key}` may not be a negative value.')
            kw[key] = value
        else:
            raise QoSOverrideError(f'Unexpected key `{key}` for QoS profile.')
    try:
        return QoSProfile(**kw)
    except InvalidQoSProfileException as exc:
        raise QoSOverrideError(str(exc)) from None


def load_overrides(path: str | Path) -> dict[str, QoSProfile]:
    """Read a ``--qos-profile-overrides-path`` file: {topic: QoSProfile}."""
    try:
        data = yaml.safe_load(Path(path).read_text()) or {}
    except (OSError, yaml.YAMLError) as exc:
        raise QoSOverrideError(f'cannot read {path}: {exc}') from None
    if not isinstance(data, dict):
        raise QoSOverrideError(f'{path}: expected a mapping of topic names to QoS profiles')
    return {topic: profile_from_dict(entry or {}) for topic, entry in data.items()}


def recorded_offers(bag_dir: Path) -> dict[str, list[dict[str, Any]]]:
    """{topic: recorded offered QoS dicts} from the bag's metadata.yaml ({} without one)."""
    meta = bag_dir / 'metadata.yaml'
    if not bag_dir.is_dir() or not meta.is_file():
        return {}
    try:
        info = yaml.safe_load(meta.read_text())['rosbag2_bagfile_information']
        out = {}
        for entry in info.get('topics_with_message_count') or []:
            topic = entry['topic_metadata']
            offers = topic.get('offered_qos_profiles') or []
            if isinstance(offers, str):  # metadata versions before 9: a YAML string
                offers = yaml.safe_load(offers) or []
            out[topic['name']] = list(offers)
        return out
    except (yaml.YAMLError, KeyError, TypeError):
        return {}


def adapt_recorded(offers: list[dict[str, Any]]) -> QoSProfile:
    """rosbag2's offer for a topic recorded with these offers (history KEEP_LAST 10)."""
    if not offers:
        return rosbag2_default()
    try:
        profiles = [profile_from_dict(o, recorded=True) for o in offers]
    except QoSOverrideError:
        return rosbag2_default()
    first = profiles[0]
    if any(getattr(p, k) != getattr(first, k) for p in profiles[1:] for k in _SAME_KEYS):
        return rosbag2_default()
    first.history = QoSHistoryPolicy.KEEP_LAST
    first.depth = DEFAULT_DEPTH
    return first


# --- what the recorder subscribes with and stores ---------------------------------------------

def qos_dict(q: QoSProfile) -> dict[str, Any]:
    """An offered QoS profile as rosbag2 (metadata version 9) stores it."""
    def dur(d: Any) -> dict[str, int]:
        return {'sec': d.nanoseconds // NS, 'nsec': d.nanoseconds % NS}
    return {'history': q.history.name.lower(), 'depth': q.depth,
            'reliability': q.reliability.name.lower(), 'durability': q.durability.name.lower(),
            'deadline': dur(q.deadline), 'lifespan': dur(q.lifespan),
            'liveliness': q.liveliness.name.lower(),
            'liveliness_lease_duration': dur(q.liveliness_lease_duration),
            'avoid_ros_namespace_conventions': q.avoid_ros_namespace_conventions}


def endpoints_hash(infos: list[Any]) -> str:
    """The publishers' common type hash 'RIHS01_...' ('' if none or if they disagree)."""
    hashes = {(i.topic_type_hash.version, bytes(i.topic_type_hash.value)) for i in infos
              if i.topic_type_hash.version > 0}
    if len(hashes) != 1:
        return ''
    version, value = hashes.pop()
    return f'RIHS{version:02d}_{value.hex()}' if version == 1 else ''


def adapted_qos(infos: list[Any]) -> QoSProfile:
    """Subscription QoS compatible with every publisher (rosbag2's rule), KEEP_ALL history."""
    reliable = bool(infos) and all(i.qos_profile.reliability == ReliabilityPolicy.RELIABLE
                                   for i in infos)
    latched = bool(infos) and all(i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
                                  for i in infos)
    return QoSProfile(history=HistoryPolicy.KEEP_ALL,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)
