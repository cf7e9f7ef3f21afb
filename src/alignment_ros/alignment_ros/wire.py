"""Stream messages read from the bytes the wire carries (CDR), with rosbags' generated readers.

rclpy hands a subscription its message as an instance of the message's Python class, built
through the constructor of every nested message; rosbags' reader of the same bytes builds plain
dataclasses with the same fields (fixed-size arrays as numpy arrays, as rclpy's) in a fraction of
the time (an Odometry: a quarter to a fifth; bench/dds_cost.py measures both). The nodes only read their
inputs' fields, so they take their streams this way (`CountingNode.stream_subscription`). Bytes
that are not a message of the type raise MalformedMessageError, which the subscription counts and
reports: through rclpy they would never have reached the node, nor been counted."""
from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

from rosbags.serde import SerdeError
from rosbags.typesys import Stores, get_typestore

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


class MalformedMessageError(ValueError):
    """Bytes that are not a CDR message of the type expected."""


def type_name(msg_type: type) -> str:
    """'package/msg/Name' of an rclpy message class (e.g. nav_msgs/msg/Odometry)."""
    package = msg_type.__module__.split('.')[0]
    return f'{package}/msg/{msg_type.__name__}'


def reader(msg_type: type) -> Callable[[bytes], Any]:
    """A function from a message's serialized bytes (as a raw subscription receives them) to the
    message, as rosbags' dataclass of the same type; MalformedMessageError if they are not one."""
    name = type_name(msg_type)
    if name not in TYPESTORE.fielddefs:
        raise KeyError(f'{name}: not a ROS 2 Jazzy message type rosbags knows')
    deserialize = TYPESTORE.deserialize_cdr

    def read(raw: bytes) -> Any:
        try:
            return deserialize(raw, name)
        except (SerdeError, UnicodeDecodeError, struct.error, IndexError, ValueError) as e:
            raise MalformedMessageError(f'{len(raw)} bytes are not a {name}: {e}') from None
    return read
