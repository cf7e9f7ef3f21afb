"""Scenario parameters as typed ROS parameters.

Every simulation node declares the whole scenario, flattened with dotted names
(`ship.sea_state`, `aircraft.lever_arm_m`, ...), with descriptors; one params file (written
by run_graph from the scenario YAML) configures the whole graph. Values are validated by
building `alignment_core.scenario.Scenario` at start-up and in the on-set callback, which
rejects any change while the node runs (the simulation is defined by its start values)
unless the name is in `dynamic`.
"""
from __future__ import annotations

import dataclasses
import typing

from rcl_interfaces.msg import ParameterDescriptor, ParameterType, SetParametersResult

from alignment_core import validation as core_config
from alignment_core.config import scenario as core_scenario


def _flatten(cls, prefix: str = '') -> list[tuple[str, typing.Any, typing.Any]]:
    out = []
    hints = typing.get_type_hints(cls)
    default = cls()
    for f in dataclasses.fields(cls):
        tp = hints[f.name]
        val = getattr(default, f.name)
        name = f'{prefix}{f.name}'
        if dataclasses.is_dataclass(tp):
            out += _flatten(tp, name + '.')
        else:
            out.append((name, tp, val))
    return out


def _ptype(tp) -> int:
    if tp is bool:
        return ParameterType.PARAMETER_BOOL
    if tp is int:
        return ParameterType.PARAMETER_INTEGER
    if tp is float:
        return ParameterType.PARAMETER_DOUBLE
    if typing.get_origin(tp) is tuple:
        return ParameterType.PARAMETER_DOUBLE_ARRAY
    return ParameterType.PARAMETER_STRING


def _ros_value(tp, val):
    if typing.get_origin(tp) is tuple:
        return [float(x) for x in val]
    return val


def nest(flat: dict[str, typing.Any]) -> dict:
    out: dict = {}
    for k, v in flat.items():
        cur = out
        parts = k.split('.')
        for p in parts[:-1]:
            cur = cur.setdefault(p, {})
        cur[parts[-1]] = list(v) if isinstance(v, (list, tuple)) else v
    return out


def flat_scenario(sc: core_scenario.Scenario) -> dict[str, typing.Any]:
    """Dotted-name -> value for a params file."""
    def walk(d, prefix=''):
        for k, v in d.items():
            if isinstance(v, dict):
                yield from walk(v, f'{prefix}{k}.')
            else:
                yield f'{prefix}{k}', v
    return dict(walk(core_config.to_dict(sc)))


class ScenarioParameters:
    """Declares the scenario on `node`, validates it, and guards changes."""

    def __init__(self, node, dynamic: tuple[str, ...] = ()) -> None:
        self.node = node
        self.dynamic = set(dynamic)
        self.fields = _flatten(core_scenario.Scenario)
        for name, tp, val in self.fields:
            node.declare_parameter(name, _ros_value(tp, val), ParameterDescriptor(
                name=name, type=_ptype(tp),
                description=f'scenario value {name} (see config/scenarios/*.yaml)'))
        self.scenario = self._build({})          # raises ConfigError on invalid start values
        self.started = True
        node.add_on_set_parameters_callback(self._on_set)

    def _build(self, changes: dict) -> core_scenario.Scenario:
        flat = {}
        for name, _, _ in self.fields:
            flat[name] = changes.get(name, self.node.get_parameter(name).value)
        return core_scenario.build_scenario(nest(flat))

    def _on_set(self, params) -> SetParametersResult:
        names = {p.name for p in params}
        ours = {n for n, _, _ in self.fields}
        frozen = sorted((names & ours) - self.dynamic)
        if frozen:
            return SetParametersResult(successful=False, reason=(
                f"scenario parameters are fixed while the node runs: {', '.join(frozen)}"))
        try:
            self._build({p.name: p.value for p in params if p.name in ours})
        except core_config.ConfigError as e:
            return SetParametersResult(successful=False, reason=str(e))
        return SetParametersResult(successful=True)
