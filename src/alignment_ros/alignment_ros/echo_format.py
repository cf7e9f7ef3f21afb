"""Format rclpy messages like ``ros2 topic echo`` (YAML) and ``ros2 topic echo --csv``.

rosidl_runtime_py is not available here, so its ``message_to_yaml`` / ``message_to_csv`` are
rebuilt from each message's ``get_fields_and_field_types()`` and ``SLOT_TYPES``. The YAML text
is emitted by PyYAML with the same settings ros2 uses (``allow_unicode=True``, unlimited width,
field order kept, block style unless ``flow_style``), so floats print as Python's ``repr``
(``1.0e-05`` in YAML's spelling), strings are quoted only when YAML needs it (``''``,
``'1.5'``, ``'yes'``) and ``byte`` fields print as characters. ``no_arr`` replaces each array
field by ``<array type: double[9]>`` / ``<sequence type: T, length: n>`` and ``no_str`` each
string by ``<string length: <n>>``, as ros2's ``--no-arr`` / ``--no-str``. ``ros2 topic echo``
prints each document followed by a ``---`` line (echo.py adds it).
"""
from __future__ import annotations

import array
import sys
from typing import Any

import numpy
import yaml
from rosidl_parser import definition

ECHO_TRUNCATE_LENGTH = 128
"""``ros2 topic echo`` truncates arrays, bytes and strings to this length unless ``--full-length``."""

_SCALARS = (bool, int, float)


class _EchoDumper(yaml.Dumper):
    """PyYAML dumper that keeps dict insertion order (message field order), as ros2 does."""


def _represent_dict(dumper: yaml.Dumper, data: dict) -> yaml.nodes.MappingNode:
    items = [(dumper.represent_data(k), dumper.represent_data(v)) for k, v in data.items()]
    return yaml.nodes.MappingNode('tag:yaml.org,2002:map', items)


_EchoDumper.add_representer(dict, _represent_dict)


def _is_message(value: Any) -> bool:
    return hasattr(value, 'get_fields_and_field_types')


def _is_array(value: Any) -> bool:
    return isinstance(value, (list, tuple, array.array, numpy.ndarray))


def _fields(msg: Any) -> list[tuple[str, Any]]:
    """(field name, rosidl_parser type) of each field, in .msg order."""
    return list(zip(msg.get_fields_and_field_types().keys(), msg.SLOT_TYPES))


def _type_name(value_type: Any) -> str:
    if isinstance(value_type, definition.BasicType):
        return value_type.typename
    if isinstance(value_type, definition.AbstractString):
        return 'string'
    if isinstance(value_type, definition.AbstractWString):
        return 'wstring'
    if isinstance(value_type, definition.NamedType):
        return value_type.name
    if isinstance(value_type, definition.NamespacedType):
        return '/'.join(value_type.namespaced_name())
    return 'unknown'


def abbreviate_array(value: Any, field_type: Any) -> str:
    """What ``--no-arr`` prints instead of an array field's elements."""
    name = _type_name(field_type.value_type)
    if isinstance(field_type, definition.Array):
        return f'<array type: {name}[{field_type.size}]>'
    if isinstance(field_type, definition.BoundedSequence):
        return f'<sequence type: {name}[{field_type.maximum_size}], length: {len(value)}>'
    if isinstance(field_type, definition.UnboundedSequence):
        return f'<sequence type: {name}, length: {len(value)}>'
    return 'unknown'


def _string_length(value: str) -> str:
    """What ``--no-str`` prints instead of a string."""
    return f'<string length: <{len(value)}>>'


def _convert(value: Any, field_type: Any, truncate_length: int | None, no_arr: bool,
             no_str: bool) -> Any:
    """Convert one field value to plain Python data, the way ``ros2 topic echo`` does.

    ``field_type`` is None for array elements: ``--no-arr`` abbreviates fields only.
    """
    if isinstance(value, bytes):
        if truncate_length is not None and len(value) > truncate_length:
            return ''.join(chr(c) for c in value[:truncate_length]) + '...'
        return ''.join(chr(c) for c in value)
    if isinstance(value, str):
        if no_str:
            return _string_length(value)
        if truncate_length is not None and len(value) > truncate_length:
            return value[:truncate_length] + '...'
        return value
    if _is_array(value):
        if no_arr and field_type is not None:
            return abbreviate_array(value, field_type)
        kind = tuple if isinstance(value, tuple) else list
        truncated = truncate_length is not None and len(value) > truncate_length
        items = value[:truncate_length] if truncated else value
        out = [_convert(v, None, truncate_length, no_arr, no_str) for v in items]
        if truncated:
            out.append('...')
        return kind(out)
    if isinstance(value, numpy.generic):
        return value.item()
    if isinstance(value, _SCALARS) or value is None:
        return value
    return to_dict(value, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str)


def to_dict(msg: Any, *, truncate_length: int | None = None, no_arr: bool = False,
            no_str: bool = False) -> dict[str, Any]:
    """Return the message as an ordered dict of plain Python values (field order of the .msg)."""
    return {
        name: _convert(getattr(msg, name, None), ftype, truncate_length, no_arr, no_str)
        for name, ftype in _fields(msg)
    }


def to_yaml(msg: Any, *, truncate_length: int | None = None, no_arr: bool = False,
            no_str: bool = False, flow_style: bool = False) -> str:
    """Return the YAML text ``ros2 topic echo`` prints for ``msg`` (without the ``---`` line).

    ``truncate_length=None`` is ``ros2 topic echo --full-length``; the ros2 default is
    :data:`ECHO_TRUNCATE_LENGTH`. ``flow_style`` is ``--flow-style`` (``{a: 1, b: [0.0]}``).
    """
    return yaml.dump(
        to_dict(msg, truncate_length=truncate_length, no_arr=no_arr, no_str=no_str),
        Dumper=_EchoDumper,
        allow_unicode=True,
        width=sys.maxsize,
        default_flow_style=flow_style,
    )


# --- CSV ------------------------------------------------------------------------------------

def _csv_cells(value: Any, field_type: Any, truncate_length: int | None, no_arr: bool,
               no_str: bool) -> list[str]:
    """Flatten one value into CSV cells the way ``ros2 topic echo --csv`` prints them."""
    if _is_array(value):
        if no_arr and field_type is not None:
            return [abbreviate_array(value, field_type)]
        if len(value) == 0:
            return ['']  # ros2 prints an empty cell for an empty sequence
        cells: list[str] = []
        for i, v in enumerate(value):
            if truncate_length is not None and i >= truncate_length:
                cells.append('...')
                break
            cells.extend(_csv_cells(v, None, truncate_length, no_arr, no_str))
        return cells
    if isinstance(value, str) and no_str:
        return [_string_length(value)]
    if isinstance(value, bytes):
        if truncate_length is not None and len(value) > truncate_length:
            value = value[:truncate_length] + b'...'
        return [str(value)]
    if isinstance(value, str):
        if truncate_length is not None and len(value) > truncate_length:
            value = value[:truncate_length] + '...'
        return [str(value)]
    if isinstance(value, (*_SCALARS, numpy.number, numpy.bool_)):
        return [str(value)]
    cells = []
    for name, ftype in _fields(value):
        cells.extend(_csv_cells(getattr(value, name), ftype, truncate_length, no_arr, no_str))
    return cells


def _csv_names(prefix: str, value: Any, field_type: Any, truncate_length: int | None,
               no_arr: bool) -> list[str]:
    """Column names matching :func:`_csv_cells`: dotted fields, ``[i]`` for array elements."""
    if _is_array(value):
        if len(value) == 0 or (no_arr and field_type is not None):
            return [prefix]
        names: list[str] = []
        for i, v in enumerate(value):
            if truncate_length is not None and i >= truncate_length:
                names.append(f'{prefix}[...]')
                break
            names.extend(_csv_names(f'{prefix}[{i}]', v, None, truncate_length, no_arr))
        return names
    if _is_message(value):
        names = []
        for name, ftype in _fields(value):
            child = f'{prefix}.{name}' if prefix else name
            names.extend(_csv_names(child, getattr(value, name), ftype, truncate_length, no_arr))
        return names
    return [prefix]


def to_csv_row(msg: Any, *, truncate_length: int | None = None, no_arr: bool = False,
               no_str: bool = False) -> str:
    """Return the line ``ros2 topic echo --csv`` prints for ``msg`` (no trailing newline).

    Values are ``str()`` of the Python values (floats as ``repr``, booleans ``True``/``False``);
    nested messages and arrays are flattened depth-first; an empty sequence is one empty cell.
    """
    return ','.join(_csv_cells(msg, None, truncate_length, no_arr, no_str))


def to_csv_header(msg: Any, *, truncate_length: int | None = None, no_arr: bool = False) -> str:
    """Return the column names matching :func:`to_csv_row` for this message.

    Names are dotted field paths, array elements get ``[i]`` suffixes
    (``orientation_covariance[0]``, ``status[0].name``); with ``no_arr`` an array field is one
    column. Sequences have a variable length, so the header is per message: it matches rows of
    messages whose sequences have the same sizes. ros2 itself prints no header.
    """
    return ','.join(_csv_names('', msg, None, truncate_length, no_arr))
