"""Format rclpy messages like ``ros2 topic echo`` (YAML) and ``ros2 topic echo --csv``.

rosidl_runtime_py is not available here, so the conversion is rebuilt from each message's
``get_fields_and_field_types()``. The YAML text is emitted by PyYAML with the same settings
ros2 uses (block style, ``allow_unicode=True``, unlimited width, field order kept), so
floats print as Python's ``repr`` (``1.0e-05`` in YAML's spelling), strings are quoted only
when YAML needs it (``''``, ``'1.5'``, ``'yes'``) and ``byte`` fields print as characters.
``ros2 topic echo`` prints each document followed by a ``---`` line (echo.py adds it).
"""
from __future__ import annotations

import array
import sys
from typing import Any

import numpy
import yaml

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


def _convert(value: Any, truncate_length: int | None) -> Any:
    """Convert one field value to plain Python data, the way ``ros2 topic echo`` does."""
    if isinstance(value, bytes):
        if truncate_length is not None and len(value) > truncate_length:
            return ''.join(chr(c) for c in value[:truncate_length]) + '...'
        return ''.join(chr(c) for c in value)
    if isinstance(value, str):
        if truncate_length is not None and len(value) > truncate_length:
            return value[:truncate_length] + '...'
        return value
    if _is_array(value):
        kind = tuple if isinstance(value, tuple) else list
        truncated = truncate_length is not None and len(value) > truncate_length
        items = value[:truncate_length] if truncated else value
        out = [_convert(v, truncate_length) for v in items]
        if truncated:
            out.append('...')
        return kind(out)
    if isinstance(value, numpy.generic):
        return value.item()
    if isinstance(value, _SCALARS) or value is None:
        return value
    return to_dict(value, truncate_length=truncate_length)


def to_dict(msg: Any, *, truncate_length: int | None = None) -> dict[str, Any]:
    """Return the message as an ordered dict of plain Python values (field order of the .msg)."""
    return {
        name: _convert(getattr(msg, name, None), truncate_length)
        for name in msg.get_fields_and_field_types()
    }


def to_yaml(msg: Any, *, truncate_length: int | None = None) -> str:
    """Return the YAML text ``ros2 topic echo`` prints for ``msg`` (without the ``---`` line).

    ``truncate_length=None`` is ``ros2 topic echo --full-length``; the ros2 default is
    :data:`ECHO_TRUNCATE_LENGTH`.
    """
    return yaml.dump(
        to_dict(msg, truncate_length=truncate_length),
        Dumper=_EchoDumper,
        allow_unicode=True,
        width=sys.maxsize,
        default_flow_style=False,
    )


# --- CSV ------------------------------------------------------------------------------------

def _csv_cells(value: Any, truncate_length: int | None) -> list[str]:
    """Flatten one value into CSV cells the way ``ros2 topic echo --csv`` prints them."""
    if _is_array(value):
        if len(value) == 0:
            return ['']  # ros2 prints an empty cell for an empty sequence
        cells: list[str] = []
        for i, v in enumerate(value):
            if truncate_length is not None and i >= truncate_length:
                cells.append('...')
                break
            cells.extend(_csv_cells(v, truncate_length))
        return cells
    if isinstance(value, (bytes, str)):
        if truncate_length is not None and len(value) > truncate_length:
            value = value[:truncate_length] + (b'...' if isinstance(value, bytes) else '...')
        return [str(value)]
    if isinstance(value, (*_SCALARS, numpy.number, numpy.bool_)):
        return [str(value)]
    cells = []
    for name in value.get_fields_and_field_types():
        cells.extend(_csv_cells(getattr(value, name), truncate_length))
    return cells


def _csv_names(prefix: str, value: Any, truncate_length: int | None) -> list[str]:
    """Column names matching :func:`_csv_cells`: dotted fields, ``[i]`` for array elements."""
    if _is_array(value):
        if len(value) == 0:
            return [prefix]
        names: list[str] = []
        for i, v in enumerate(value):
            if truncate_length is not None and i >= truncate_length:
                names.append(f'{prefix}[...]')
                break
            names.extend(_csv_names(f'{prefix}[{i}]', v, truncate_length))
        return names
    if _is_message(value):
        names = []
        for name in value.get_fields_and_field_types():
            child = f'{prefix}.{name}' if prefix else name
            names.extend(_csv_names(child, getattr(value, name), truncate_length))
        return names
    return [prefix]


def to_csv_row(msg: Any, *, truncate_length: int | None = None) -> str:
    """Return the line ``ros2 topic echo --csv`` prints for ``msg`` (no trailing newline).

    Values are ``str()`` of the Python values (floats as ``repr``, booleans ``True``/``False``);
    nested messages and arrays are flattened depth-first; an empty sequence is one empty cell.
    """
    return ','.join(_csv_cells(msg, truncate_length))


def to_csv_header(msg: Any, *, truncate_length: int | None = None) -> str:
    """Return the column names matching :func:`to_csv_row` for this message.

    Names are dotted field paths, array elements get ``[i]`` suffixes
    (``orientation_covariance[0]``, ``status[0].name``). Sequences have a variable length, so
    the header is per message: it matches rows of messages whose sequences have the same sizes.
    ros2 itself prints no header.
    """
    return ','.join(_csv_names('', msg, truncate_length))
