"""Scenario parameters as typed ROS parameters.

One params file configures the whole graph: its `/**` section holds the scenario as given (the
scenario file's keys and the --set overrides, flattened with dotted names: `ship.sea_state`,
`aircraft.lever_arm_m`, ...), not the resolved scenario. Each node declares only the keys it
reads (NODE_SCOPES), with descriptors, and resolves what it was given with
`scenario.resolve` (presets and the defaulting rules included), the same function as the
command line's --set uses: `-p aircraft.lever_arm_m:=...` moves the filter's lever arm exactly
as `--set aircraft.lever_arm_m=...` does, unless filter.lever_arm_m is given too. The declared
values are the resolved ones.

At start-up a node refuses, with one message naming the key (node_util.run): a value of the
wrong type or out of range, and a parameter that is neither its own nor a scenario key (a
scenario key of another node's sections is for that node and is ignored). Changes while the
node runs are refused (the simulation is defined by its start values) unless the name is in
`dynamic`.
"""
from __future__ import annotations

import dataclasses
import difflib
import re
import sys
import typing
from pathlib import Path

import yaml
from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    ParameterType,
    SetParametersResult,
)
from rclpy.parameter import Parameter

from alignment_core import validation as core_config
from alignment_core.config import scenario as core_scenario
from alignment_core.config.given import FOLLOWS, Scope, flatten, nest

TIMING = ('seed', 'rate_hz', 'start_time_s')
ORIGIN = ('ship.lat_deg', 'ship.lon_deg')               # the local tangent plane's origin
DECK_SPOT = ('aircraft.lever_arm_m', 'aircraft.heading_on_deck_deg')
# the streams' timing, for the ship node's run-out past the end (alignment_core/run_out.py)
RUN_OUT = ('master.rate_hz', 'master.latency_s', 'master.latency_jitter_s', 'ldv.rate_hz', 'ldv.latency_s',
           'doppler.enabled', 'doppler.rate_hz', 'doppler.latency_s', 'filter.output_rate_hz')

NODE_SCOPES: dict[str, Scope] = {
    'ship_motion_node': Scope(('name', 'duration_s', *TIMING, 'ship', *RUN_OUT)),
    'master_ins_node': Scope((*TIMING, *ORIGIN, 'master')),
    'slave_ins_node': Scope((*TIMING, *ORIGIN, 'aircraft', 'imu', 'reference_ins')),
    # the deck spot and the catapult give the LDV's origin, heading and track length by default
    'ldv_node': Scope((*TIMING, *ORIGIN, *DECK_SPOT, 'aircraft.catapult', 'ldv', 'doppler')),
    # what a user knows: the IMU rate, the origin, the surveyed deck spot; no simulation section
    # (the seed and the survey sigma only to draw the survey error: config/given.py; the LDV's kind)
    'alignment_filter_node': Scope(('rate_hz', *ORIGIN, *DECK_SPOT, 'seed', 'aircraft.lever_arm_survey_sigma_m',
                                    'ldv.mode', 'filter')),
    'air_data_node': Scope((*TIMING, *ORIGIN, 'fads')),
    # the installed sensor's known calibration (port geometry, eps(M)) and the IMU rate; never
    # the sensor's noise truth or faults
    'air_data_filter_node': Scope(('rate_hz', *ORIGIN, 'fads.rate_hz', 'fads.cone_deg', 'fads.clock_deg',
                                   'fads.eps_mach', 'fads.eps', 'air_data_filter')),
}
"""The scenario keys (sections or single keys) each node reads."""


def _flatten(cls, prefix: str = '') -> list[tuple[str, typing.Any, typing.Any]]:
    out = []
    hints = typing.get_type_hints(cls)
    default = cls()
    for f in dataclasses.fields(cls):
        tp = hints[f.name]
        name = f'{prefix}{f.name}'
        if dataclasses.is_dataclass(tp):
            out += _flatten(tp, name + '.')
        else:
            out.append((name, tp, getattr(default, f.name)))
    return out


FIELDS = _flatten(core_scenario.Scenario)
"""(dotted name, type, default) of every scenario key."""
SCENARIO_KEYS = frozenset(name for name, _, _ in FIELDS)

UNITS = {'s': 's', 'ms': 'ms', 'deg': 'deg', 'arcmin': 'arcmin', 'arcsec': 'arcsec', 'm': 'm',
         'mps': 'm/s', 'mps2': 'm/s^2', 'hz': 'Hz', 'kn': 'knots', 'g': 'g', 'dps': 'deg/s',
         'dph': 'deg/h', 'dpsh': 'deg/sqrt(h)', 'dphps': 'deg/h/sqrt(s)', 'dphpg': 'deg/h per g',
         'ug': 'micro-g', 'ugpshz': 'micro-g/sqrt(Hz)', 'ugps': 'micro-g/sqrt(s)', 'ppm': 'ppm'}
"""Unit of a key from its name's last part (`ldv_sigma_mps`: m/s)."""

TOP_LEVEL = {'name': 'scenario name', 'description': 'one line on the scenario',
             'seed': 'seed of every simulated random draw', 'duration_s': 'length of the run',
             'rate_hz': 'sample rate of the ship truth and the aircraft IMU',
             'start_time_s': 'stamp of the first sample (simulation time)'}

RANGES = {'seed': (0, 2**63 - 1), 'rate_hz': (1.0, 2000.0), 'duration_s': (0.0, 86400.0),
          'ship.sea_state': (0, 9), 'ship.lat_deg': (-90.0, 90.0), 'ship.lon_deg': (-180.0, 360.0)}
"""Bounds stated in the descriptors (the scenario's validation has the exact rules)."""


def _ptype(tp) -> int:
    if typing.get_origin(tp) is typing.Literal:
        tp = type(typing.get_args(tp)[0])
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


def _section_doc(name: str) -> str:
    """First line of the docstring of the dataclass holding `name`'s section."""
    cls = core_scenario.Scenario
    for part in name.split('.')[:-1]:
        cls = typing.get_type_hints(cls)[part]
    return (cls.__doc__ or '').strip().splitlines()[0].rstrip('.')


def describe(name: str, tp) -> ParameterDescriptor:
    """The descriptor of scenario key `name`: type, unit, what it is, choices, bounds."""
    last = name.rsplit('.', 1)[-1]
    unit = UNITS.get(last.rsplit('_', 1)[-1]) if '_' in last else None
    what = TOP_LEVEL.get(name) or _section_doc(name)
    text = f'{name}{f" [{unit}]" if unit else ""}: {what}'
    followers = [k for k, src in FOLLOWS.items() if src == name or name.startswith(src + '.')]
    if followers:
        text += f'; sets the default of {", ".join(followers)}'
    if name in FOLLOWS:
        text += f'; default: from {FOLLOWS[name]}'
    d = ParameterDescriptor(name=name, type=_ptype(tp), description=text)
    if typing.get_origin(tp) is typing.Literal:
        d.additional_constraints = 'one of: ' + ', '.join(str(a) for a in typing.get_args(tp))
    elif typing.get_origin(tp) is tuple:
        args = typing.get_args(tp)
        d.additional_constraints = ('a list of numbers' if args[-1] is Ellipsis
                                    else f'a list of {len(args)} numbers')
    lo, hi = RANGES.get(name, (None, None))
    if isinstance(lo, int) and tp is int:
        d.integer_range = [IntegerRange(from_value=lo, to_value=hi, step=0)]
    elif lo is not None and tp is float:
        d.floating_point_range = [FloatingPointRange(from_value=lo, to_value=hi, step=0.0)]
    return d


def flat_scenario(sc: core_scenario.Scenario) -> dict[str, typing.Any]:
    """Dotted name -> value of every key of a resolved scenario."""
    return flatten(core_config.to_dict(sc))


def given_parameters(given: dict, sc: core_scenario.Scenario) -> dict[str, typing.Any]:
    """The params file entries of a scenario as given (nested; `sc` = its resolution): the
    keys given, each with its value as the nodes declare it (floats as floats)."""
    flat = flat_scenario(sc)
    return {k: flat[k] for k in flatten(given) if k in flat}


def params_file_given(path: Path, node_name: str) -> dict[str, typing.Any]:
    """The parameters a params file gives the node `node_name` (its `/**` section, then its
    own, as rcl merges them)."""
    doc = yaml.safe_load(Path(path).read_text()) or {}
    out: dict[str, typing.Any] = {}
    for key in ('/**', node_name, '/' + node_name):
        out.update((doc.get(key) or {}).get('ros__parameters') or {})
    return out


def command_line_parameters(argv: list[str], node_name: str) -> dict[str, str]:
    """NAME -> the text of each `-p NAME:=VALUE` (or `--param`, or `-p NODE:NAME:=VALUE` for
    this node) inside the `--ros-args` sections of argv."""
    out: dict[str, str] = {}
    in_ros = False
    it = iter(argv)
    for arg in it:
        if arg == '--ros-args':
            in_ros = True
        elif arg == '--':
            in_ros = False
        elif in_ros and arg in ('-p', '--param'):
            rule = next(it, '')
            name, sep, text = rule.partition(':=')
            if not sep:
                continue
            node, colon, key = name.rpartition(':')
            if colon and node.lstrip('/') != node_name:
                continue
            out[key if colon else name] = text
    return out


_EXPONENT = re.compile(r'^[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+$')
_TRUE = ('y', 'Y', 'yes', 'Yes', 'YES', 'true', 'True', 'TRUE', 'on', 'On', 'ON')
_FALSE = ('n', 'N', 'no', 'No', 'NO', 'false', 'False', 'FALSE', 'off', 'Off', 'OFF')


def ros_value(text: str) -> typing.Any:
    """The value of a `-p` rule's text as rcl types it: bool words, integers, floats, lists
    of them, otherwise a string (quotes stripped)."""
    t = text.strip()
    if len(t) >= 2 and t[0] == t[-1] and t[0] in '\'"':
        return t[1:-1]
    if t.startswith('[') and t.endswith(']'):
        items = yaml.safe_load(t) or []        # YAML 1.1 reads 1e-3 as a string; rcl as a float
        return [float(x) if isinstance(x, str) and _EXPONENT.match(x) else x for x in items]
    if t in _TRUE:
        return True
    if t in _FALSE:
        return False
    for conv in (lambda s: int(s, 0), float):
        try:
            return conv(t)
        except ValueError:
            pass
    return t


def _ros_type(value) -> Parameter.Type | None:
    try:
        return Parameter.Type.from_parameter_value(value)
    except TypeError:
        return None


def given_to(node, argv: list[str] | None = None) -> dict[str, typing.Any]:
    """Every parameter value given to `node` (params files and `-p`), as rclpy merged them,
    except that a `-p` value of another type than the params file's value of the same name
    replaces it: rcl keeps the file's value then, so `-p filter.ldv_sigma_mps:=abc` over a
    params file would be silently dropped."""
    given = {name: p.value for name, p in node._parameter_overrides.items()}
    for name, text in command_line_parameters(sys.argv if argv is None else argv, node.get_name()).items():
        ours = ros_value(text)
        if name not in given or _ros_type(ours) != _ros_type(given[name]):
            given[name] = ours
    return given


def refuse_unknown(node, argv: list[str] | None = None) -> None:
    """ConfigError naming every parameter given to `node` that it does not declare and that
    is not a scenario key (another node's)."""
    unknown = sorted(n for n in given_to(node, argv) if not node.has_parameter(n) and n not in SCENARIO_KEYS)
    if not unknown:
        return
    known = sorted(set(node.list_parameters([], 0).names) | SCENARIO_KEYS)
    hints = []
    for n in unknown:
        close = difflib.get_close_matches(n, known, n=1, cutoff=0.8)
        hints.append(f'{n} (did you mean {close[0]}?)' if close else n)
    raise core_config.ConfigError(f"{node.get_name()}: unknown parameter(s): {', '.join(hints)}")


def node_scenario(given: dict[str, typing.Any], scope: Scope) -> core_scenario.Scenario:
    """The scenario a node reading `scope` resolves from the parameters it was given (flat;
    other nodes' keys are left out). ConfigError if invalid."""
    ours = {k: v for k, v in given.items() if k in SCENARIO_KEYS and scope.covers(k)}
    return core_scenario.resolve(nest(ours), scope=scope)


class ScenarioParameters:
    """Declares the scenario keys of `scope` on `node`, resolved from what it was given, and
    guards changes. `.scenario` is the resolved scenario (keys outside the scope at their
    defaults: not to be read)."""

    def __init__(self, node, scope: Scope, dynamic: tuple[str, ...] = (),
                 argv: list[str] | None = None) -> None:
        self.node = node
        self.scope = scope
        self.dynamic = set(dynamic)
        self.fields = [(n, tp) for n, tp, _ in FIELDS if scope.covers(n)]
        ours = {n for n, _ in self.fields}
        self.given = {k: v for k, v in given_to(node, argv).items() if k in ours}
        self.scenario = node_scenario(self.given, scope)
        values = flat_scenario(self.scenario)
        for name, tp in self.fields:
            node.declare_parameter(name, _ros_value(tp, values[name]), describe(name, tp),
                                   ignore_override=True)
        node.add_on_set_parameters_callback(self._on_set)

    def _on_set(self, params) -> SetParametersResult:
        ours = {n for n, _ in self.fields}
        names = {p.name for p in params}
        frozen = sorted((names & ours) - self.dynamic)
        if frozen:
            return SetParametersResult(successful=False, reason=(
                f"scenario parameters are fixed while the node runs: {', '.join(frozen)}"))
        changes = {p.name: p.value for p in params if p.name in ours}
        if changes:
            try:
                node_scenario({**self.given, **changes}, self.scope)
            except core_config.ConfigError as e:
                return SetParametersResult(successful=False, reason=str(e))
        return SetParametersResult(successful=True)
