"""Message definitions as rosbag2 stores them in MCAP schemas, from the installed interface files.

rosbag2 (``LocalMessageDefinitionSource``) stores a type's ``.msg`` file as installed, comments
and defaults included, followed by each dependency not yet written, depth first in sorted
order, as ``\\n`` + 80 ``=`` + ``\\nMSG: pkg/Type\\n`` + its text. A type without a ``.msg`` falls
back to its ``.idl`` (``IDL:`` blocks, encoding ``ros2idl``); a type with neither gets an
empty definition (encoding ``''``). The files are found like ament_index does: ``share/PKG``
of the prefix that registers PKG. The type hash (RIHS01) is the one rosidl installed next to
the definition (``share/PKG/msg/Type.json``). No rclpy import.
"""
from __future__ import annotations

import functools
import json
import re
from pathlib import Path

from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

DELIMITER = '=' * 80 + '\n'
MAX_DEPTH = 50  # rosbag2's ROSBAG2_CPP_LOCAL_MESSAGE_DEFINITION_SOURCE_MAX_RECURSION_DEPTH
PRIMITIVES = frozenset({'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16',
                        'uint16', 'int32', 'uint32', 'int64', 'uint64', 'string'})
# the patterns rosbag2 uses: a type name, a field's type in .msg text, an include in .idl text
_TYPE_NAME = re.compile(r'^([a-zA-Z0-9_]+)/(?:msg/|srv/)?([a-zA-Z0-9_]+)$')
_MSG_FIELD_TYPE = re.compile(r'(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+')
_IDL_INCLUDE = re.compile(r'(?:^|\n)#include\s+(?:"|<)([a-zA-Z0-9_/]+)\.idl(?:"|>)')
STAMP_TYPES = frozenset({'std_msgs/Header', 'std_msgs/msg/Header', 'builtin_interfaces/Time',
                         'builtin_interfaces/msg/Time'})


class DefinitionNotFoundError(LookupError):
    """No installed interface file for a type."""


def _split(type_name: str) -> tuple[str, str]:
    m = _TYPE_NAME.match(type_name)
    if m is None:
        raise DefinitionNotFoundError(f'type name {type_name!r} not understood')
    return m.group(1), m.group(2)


@functools.cache
def _share(package: str) -> Path:
    try:
        return Path(get_package_share_directory(package))
    except (PackageNotFoundError, ValueError) as exc:
        raise DefinitionNotFoundError(f'package {package!r} is not installed') from exc


@functools.cache
def interface_text(type_name: str, ext: str = 'msg') -> str:
    """The installed ``share/PKG/msg/Type.<ext>`` of a type ('pkg/Type' or 'pkg/msg/Type')."""
    package, name = _split(type_name)
    path = _share(package) / 'msg' / f'{name}.{ext}'
    try:
        return path.read_text()
    except OSError as exc:
        raise DefinitionNotFoundError(f'{type_name}: no {path}') from exc


def msg_dependencies(text: str, package: str) -> list[str]:
    """Non-primitive field types of .msg text, as 'pkg/Type', sorted (rosbag2's std::set)."""
    deps = set()
    for m in _MSG_FIELD_TYPE.finditer(text):
        t = m.group(1)
        if t in PRIMITIVES:
            continue
        deps.add(t if '/' in t else f'{package}/{t}')
    return sorted(deps)


def _dependencies(text: str, package: str, ext: str) -> list[str]:
    if ext == 'msg':
        return msg_dependencies(text, package)
    return sorted({m.group(1) for m in _IDL_INCLUDE.finditer(text)})


def _full_text(root: str, ext: str) -> str:
    seen: set[str] = set()
    label = 'MSG' if ext == 'msg' else 'IDL'

    def append(type_name: str, depth: int) -> str:
        if depth <= 0:
            raise DefinitionNotFoundError(f'reached max recursion depth resolving {root}')
        text = interface_text(type_name, ext)
        out = text
        for dep in _dependencies(text, _split(type_name)[0], ext):
            if dep not in seen:
                seen.add(dep)
                out += '\n' + DELIMITER + f'{label}: {dep}\n' + append(dep, depth - 1)
        return out

    if ext == 'msg':
        return append(root, MAX_DEPTH)
    return DELIMITER + f'IDL: {root}\n' + append(root, MAX_DEPTH)


@functools.cache
def message_definition(type_name: str) -> tuple[str, str]:
    """(schema encoding, text) rosbag2 writes for a message type: ('ros2msg', .msg text with
    dependencies), else ('ros2idl', .idl blocks), else ('', '') when nothing is installed."""
    for ext, encoding in (('msg', 'ros2msg'), ('idl', 'ros2idl')):
        try:
            return encoding, _full_text(type_name, ext)
        except DefinitionNotFoundError:
            continue
    return '', ''


@functools.cache
def type_hash(type_name: str) -> str:
    """The RIHS01 type description hash rosidl installed for 'pkg/msg/Type' ('' if none)."""
    package, name = _split(type_name)
    try:
        doc = json.loads((_share(package) / 'msg' / f'{name}.json').read_text())
    except (DefinitionNotFoundError, OSError, ValueError):
        return ''
    full = f'{package}/msg/{name}'
    for entry in doc.get('type_hashes', []):
        if entry.get('type_name') == full:
            return str(entry.get('hash_string', ''))
    return ''


def first_field_type(type_name: str) -> str | None:
    """Type of the first field of a .msg ('pkg/Type' resolved), None if no field or no .msg."""
    try:
        text = interface_text(type_name)
    except DefinitionNotFoundError:
        return None
    package = _split(type_name)[0]
    for line in text.splitlines():
        line = line.split('#', 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        if len(parts) < 2 or '=' in parts[1] or (len(parts) > 2 and parts[2].startswith('=')):
            continue  # a constant: TYPE NAME=VALUE
        base_type = re.match(r'[a-zA-Z0-9_/]*', parts[0])
        assert base_type is not None  # '*' matches the empty string too: re.match cannot fail
        t = base_type.group(0)  # without [N] or <=N
        return t if '/' in t or t in PRIMITIVES else f'{package}/{t}'
    return None


def has_stamp(type_name: str) -> bool:
    """True if the type's first field is a std_msgs/Header or a builtin_interfaces/Time."""
    return first_field_type(type_name) in STAMP_TYPES
