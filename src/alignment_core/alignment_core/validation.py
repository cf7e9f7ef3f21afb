"""Typed, validated configuration: dataclasses built from nested dicts with clear errors.

`build(cls, data, where)` accepts only the dataclass's own keys (an unknown key is an error
naming its dotted path), converts ints to floats where a float is declared, lists to tuples,
and recurses into nested dataclasses; each dataclass checks its own ranges in `validate()`.
"""
from __future__ import annotations

import dataclasses
import math
import typing
from typing import Any


class ConfigError(ValueError):
    """A configuration value is missing, unknown, of the wrong type or out of range."""


def _convert(tp: Any, value: Any, where: str) -> Any:
    origin = typing.get_origin(tp)
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise ConfigError(f"{where}: expected a mapping, got {value!r}")
        return build(tp, value, where)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{where}: expected a number, got {value!r}")
        if not math.isfinite(float(value)):
            raise ConfigError(f"{where}: must be finite, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{where}: expected an integer, got {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: expected true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where}: expected a string, got {value!r}")
        return value
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"{where}: expected a list, got {value!r}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(args[0], v, f"{where}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise ConfigError(f"{where}: expected {len(args)} values, got {len(value)}")
        return tuple(_convert(a, v, f"{where}[{i}]") for i, (a, v) in enumerate(zip(args, value)))
    if origin is typing.Literal:
        if value not in typing.get_args(tp):
            raise ConfigError(f"{where}: must be one of {list(typing.get_args(tp))}, got {value!r}")
        return value
    raise TypeError(f"unsupported config type {tp} at {where}")


def build(cls, data: dict | None, where: str = ''):
    """Build dataclass `cls` from `data`, filling defaults; raise ConfigError naming bad keys."""
    data = {} if data is None else data
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - names)
    if unknown:
        keys = ', '.join(f"{where + '.' if where else ''}{k}" for k in unknown)
        raise ConfigError(f"unknown key(s): {keys} (allowed: {', '.join(sorted(names))})")
    kwargs = {}
    for f in dataclasses.fields(cls):
        if f.name in data:
            kwargs[f.name] = _convert(hints[f.name], data[f.name],
                                      f"{where + '.' if where else ''}{f.name}")
    obj = cls(**kwargs)
    if hasattr(obj, 'validate'):
        try:
            obj.validate()
        except ConfigError as e:
            raise ConfigError(f"{where + ': ' if where else ''}{e}") from None
    return obj


def to_dict(obj) -> dict:
    """Plain nested dict (lists for tuples) of a config dataclass."""
    def conv(v):
        if dataclasses.is_dataclass(v):
            return {f.name: conv(getattr(v, f.name)) for f in dataclasses.fields(v)}
        if isinstance(v, tuple):
            return [conv(x) for x in v]
        return v
    return conv(obj)


def require(cond: bool, msg: str) -> None:
    if not cond:
        raise ConfigError(msg)


def keyed_items(text: str, label: str, noun: str, allowed: dict[str, tuple[str, ...]]
                ) -> list[tuple[str, str, dict[str, float]]]:
    """Parse 'kind key=value ...' items separated by ';' or new lines into (where, kind, values),
    `where` naming the item for error messages (label[i] (item)); kinds and their keys from
    `allowed`; values finite numbers, each key at most once. ConfigError names the problem."""
    items = [p.strip() for p in text.replace('\n', ';').split(';')]
    out = []
    for i, item in enumerate(p for p in items if p):
        where = f"{label}[{i}] ({item!r})"
        kind, *pairs = item.split()
        require(kind in allowed, f"{where}: unknown {noun} {kind!r} (allowed: {', '.join(allowed)})")
        vals: dict[str, float] = {}
        for p in pairs:
            key, sep, val = p.partition('=')
            require(bool(sep) and bool(key) and bool(val), f"{where}: expected key=value, got {p!r}")
            require(key in allowed[kind],
                    f"{where}: unknown key {key!r} for {kind} (allowed: {', '.join(allowed[kind])})")
            require(key not in vals, f"{where}: {key} given twice")
            try:
                x = float(val)
            except ValueError:
                raise ConfigError(f"{where}: {key} must be a number, got {val!r}") from None
            require(math.isfinite(x), f"{where}: {key} must be finite, got {val!r}")
            vals[key] = x
        out.append((where, kind, vals))
    return out
