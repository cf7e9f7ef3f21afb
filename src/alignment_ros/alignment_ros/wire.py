"""Stream messages read from the bytes the wire carries (CDR), with rosbags' generated readers.

rclpy hands a subscription its message as an instance of the message's Python class, built
through the constructor of every nested message; rosbags' reader of the same bytes builds plain
dataclasses with the same fields (fixed-size arrays as numpy arrays, read-only) in a fraction of
the time (an Odometry: a quarter to a fifth; bench/dds_cost.py measures both). The nodes only read
their inputs' fields, so they take their streams this way (`CountingNode.stream_subscription`).

rosbags is stricter than rclpy: it refuses more than 3 bytes after a message's end, and a string
that is not UTF-8 (rclpy substitutes U+FFFD). Bytes rosbags refuses are read by rclpy instead, so
a node takes exactly the messages a typed subscription would have; bytes neither can read (cut
short, a length beyond the data, no CDR header) raise MalformedMessageError, which the
subscription counts and reports where a typed subscription would have dropped them unseen."""
from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.serialization import deserialize_message
from rosbags.serde import SerdeError
from rosbags.typesys import Stores, get_typestore

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
_RMW_ERROR = rclpy_implementation.RMWError


class MalformedMessageError(ValueError):
    """Bytes that are not a CDR message of the type expected."""


def type_name(msg_type: type) -> str:
    """'package/msg/Name' of an rclpy message class (e.g. nav_msgs/msg/Odometry)."""
    package = msg_type.__module__.split('.')[0]
    return f'{package}/msg/{msg_type.__name__}'


def reader(msg_type: type) -> Callable[[bytes], Any]:
    """A function from a message's serialized bytes (as a raw subscription receives them) to the
    message: rosbags' dataclass of the same type, or rclpy's message where only rclpy reads them;
    MalformedMessageError if neither does."""
    name = type_name(msg_type)
    if name not in TYPESTORE.fielddefs:
        raise KeyError(f'{name}: not a ROS 2 Jazzy message type rosbags knows')
    deserialize = TYPESTORE.deserialize_cdr

    def read(raw: bytes) -> Any:
        try:
            return deserialize(raw, name)
        except (SerdeError, UnicodeDecodeError, struct.error, IndexError, ValueError) as e:
            strict = e
        try:
            return deserialize_message(raw, msg_type)
        except _RMW_ERROR:
            raise MalformedMessageError(f'{len(raw)} bytes are not a {name}: {strict}') from None
    return read
