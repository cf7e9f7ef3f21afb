"""Argument types and ``--qos-*`` options as ros2cli defines them (ros2cli is not installed here).

echo.py and player.py use these so that their options parse, default and fail like
``ros2 topic echo`` and ``ros2 bag play``: same choices, same messages, same QoS a given
command line resolves to (a preset profile, overridden field by field, then for echo adapted to
the publishers in the graph).
"""
from __future__ import annotations

import argparse
import copy
from typing import Any, TypeVar

from rclpy.duration import Duration
from rclpy.qos import (
    QoSDurabilityPolicy,
    QoSHistoryPolicy,
    QoSLivelinessPolicy,
    QoSPresetProfiles,
    QoSProfile,
    QoSReliabilityPolicy,
)

QOS_OPTION_DESTS = ('qos_reliability', 'qos_durability', 'qos_depth', 'qos_history',
                    'qos_liveliness', 'qos_liveliness_lease_duration_seconds')
"""The options that, given, make ``ros2 topic echo`` use the profile as set (no adaptation)."""


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """(own arguments, ROS arguments) of ``argv`` without the program name: the ROS ones are
    the ``--ros-args ... [--]`` sections. Unlike rclpy's ``remove_ros_args`` this keeps
    ``old:=new`` words (``ros2 bag play --remap old:=new``) as own arguments."""
    own: list[str] = []
    ros: list[str] = []
    in_ros = False
    for arg in argv:
        if arg == '--ros-args':
            in_ros = True
            ros.append(arg)
        elif in_ros and arg == '--':
            in_ros = False
            ros.append(arg)
        else:
            (ros if in_ros else own).append(arg)
    return own, ros


# --- argument types (ros2cli's messages) -----------------------------------------------------

def positive_float(text: str) -> float:
    """ros2topic's ``positive_float``: a float > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError('Expects a floating point number') from None
    if value <= 0.0:
        raise argparse.ArgumentTypeError('Value must be positive')
    return value


def unsigned_int(text: str) -> int:
    """ros2cli's ``unsigned_int``: an int >= 0 (``-l -1`` is refused)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError('value must be non-negative integer')
    return value


NumberT = TypeVar('NumberT', int, float)


def number(text: str, kind: type[NumberT]) -> NumberT:
    """`text` as a float or int, or ros2bag's type error ("X is not the valid type (float)")."""
    try:
        return kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text} is not the valid type ({kind.__name__})') from None


def check_positive_float(text: str) -> float:
    """ros2bag's ``check_positive_float``: a float > 0 (``--rate``)."""
    value = number(text, float)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f'{text} is not in the valid range (> 0.0)')
    return value


def check_not_negative_float(text: str) -> float:
    """ros2bag's ``check_not_negative_float``: a float >= 0 (``--start-offset``)."""
    value = number(text, float)
    if value < 0.0:
        raise argparse.ArgumentTypeError(f'Value {text} is less than zero.')
    return value


def check_not_negative_int(text: str) -> int:
    """ros2bag's ``check_not_negative_int``: an int >= 0 (``--wait-for-all-acked``)."""
    value = number(text, int)
    if value < 0:
        raise argparse.ArgumentTypeError(f'Value {value} is less than zero.')
    return value


def bag_positive_float(text: str) -> float:
    """ros2bag play's own ``positive_float`` (``--clock``, ``--delay``): a float > 0.

    It raises ValueError, so argparse reports "invalid positive_float value: '0'".
    """
    value = float(text)
    if value <= 0:
        raise ValueError(f'Value {value} is less than or equal to zero.')
    return value


bag_positive_float.__name__ = 'positive_float'


# --- QoS options -----------------------------------------------------------------------------

def preset(short_key: str) -> QoSProfile:
    """A copy of rclpy's preset profile ``short_key`` (the presets themselves are shared)."""
    return copy.copy(QoSPresetProfiles.get_from_short_key(short_key))


def add_qos_arguments(parser: argparse.ArgumentParser, verb: str, default_profile: str) -> None:
    """The ``--qos-*`` options of ``ros2 topic echo`` / ``pub`` (``verb``: 'subscribe')."""
    parser.add_argument(
        '--qos-profile', choices=QoSPresetProfiles.short_keys(), default=default_profile,
        help=f'Quality of service preset profile to {verb} with (default: {default_profile})')
    default = preset(default_profile)
    parser.add_argument(
        '--qos-depth', metavar='N', type=int,
        help=f'Queue size setting to {verb} with (overrides depth value of --qos-profile option)')
    parser.add_argument(
        '--qos-history', choices=QoSHistoryPolicy.short_keys(),
        help=(f'History of samples setting to {verb} with (overrides history value of '
              f'--qos-profile option, default: {default.history.short_key})'))
    parser.add_argument(
        '--qos-reliability', choices=QoSReliabilityPolicy.short_keys(),
        help=(f'Quality of service reliability setting to {verb} with (overrides reliability '
              'value of --qos-profile option, default: Compatible profile with running endpoints )'))
    parser.add_argument(
        '--qos-durability', choices=QoSDurabilityPolicy.short_keys(),
        help=(f'Quality of service durability setting to {verb} with (overrides durability '
              'value of --qos-profile option, default: Compatible profile with running endpoints )'))
    parser.add_argument(
        '--qos-liveliness', choices=QoSLivelinessPolicy.short_keys(),
        help=(f'Quality of service liveliness setting to {verb} with (overrides liveliness '
              'value of --qos-profile option'))
    parser.add_argument(
        '--qos-liveliness-lease-duration-seconds', type=float,
        help=(f'Quality of service liveliness lease duration setting to {verb} with '
              '(overrides liveliness lease duration value of --qos-profile option'))


def qos_options_given(args: argparse.Namespace) -> bool:
    """True if any ``--qos-*`` option other than ``--qos-profile`` was given."""
    return any(getattr(args, d) is not None for d in QOS_OPTION_DESTS)


def qos_profile_from_args(args: argparse.Namespace) -> QoSProfile:
    """The preset ``--qos-profile`` with each given ``--qos-*`` option applied, as ros2cli does
    (a depth of 0 keeps the preset's; TRANSIENT_LOCAL with depth 0 gets depth 1)."""
    profile = preset(args.qos_profile)
    if args.qos_history:
        profile.history = QoSHistoryPolicy.get_from_short_key(args.qos_history)
    if args.qos_durability:
        profile.durability = QoSDurabilityPolicy.get_from_short_key(args.qos_durability)
    if args.qos_reliability:
        profile.reliability = QoSReliabilityPolicy.get_from_short_key(args.qos_reliability)
    if args.qos_liveliness:
        profile.liveliness = QoSLivelinessPolicy.get_from_short_key(args.qos_liveliness)
    lease = args.qos_liveliness_lease_duration_seconds
    if lease and lease >= 0:
        profile.liveliness_lease_duration = Duration(seconds=lease)
    if args.qos_depth and args.qos_depth >= 0:
        profile.depth = args.qos_depth
    elif profile.durability == QoSDurabilityPolicy.TRANSIENT_LOCAL and profile.depth == 0:
        profile.depth = 1
    return profile


def adapt_to_publishers(profile: QoSProfile, offered: list[Any]) -> tuple[QoSProfile, list[str]]:
    """``ros2 topic echo``'s QoS without ``--qos-*`` overrides: the preset, RELIABLE if every
    publisher offers it (else BEST_EFFORT), TRANSIENT_LOCAL if every publisher offers it (else
    VOLATILE); the preset as is when there is no publisher. ``offered``: the publishers'
    QoSProfiles. Returns the profile and the notes ros2 prints for a mixed offer."""
    notes: list[str] = []
    if not offered:
        return profile, notes
    reliable = sum(p.reliability == QoSReliabilityPolicy.RELIABLE for p in offered)
    latched = sum(p.durability == QoSDurabilityPolicy.TRANSIENT_LOCAL for p in offered)
    if reliable == len(offered):
        profile.reliability = QoSReliabilityPolicy.RELIABLE
    else:
        if reliable:
            notes.append('Some, but not all, publishers are offering QoSReliabilityPolicy.RELIABLE. '
                         'Falling back to QoSReliabilityPolicy.BEST_EFFORT as it will connect to '
                         'all publishers')
        profile.reliability = QoSReliabilityPolicy.BEST_EFFORT
    if latched == len(offered):
        profile.durability = QoSDurabilityPolicy.TRANSIENT_LOCAL
    else:
        if latched:
            notes.append('Some, but not all, publishers are offering '
                         'QoSDurabilityPolicy.TRANSIENT_LOCAL. Falling back to '
                         'QoSDurabilityPolicy.VOLATILE as it will connect to all publishers')
        profile.durability = QoSDurabilityPolicy.VOLATILE
    return profile, notes
