"""Node parameters: each node declares only the scenario keys it reads, resolves what it is
given with the command line's resolver (so `-p KEY:=V` on a node gives the scenario `--set
KEY=V` gives), and refuses unknown and wrong-typed parameters. The nodes are built in-process
on a private ROS domain (no process, nothing spun)."""
from __future__ import annotations

import dataclasses
import importlib
import sys
from pathlib import Path

import pytest
import rclpy
from rcl_interfaces.msg import ParameterType

from alignment_core.config import scenario
from alignment_core.estimation.config import FilterConfig
from alignment_core.validation import ConfigError
from alignment_ros import domain, params
from alignment_ros.graph import params_yaml

ROOT = Path(__file__).resolve().parents[2]
GRAPH_YAML = ROOT / 'config/params/graph.yaml'                # the default scenario's
PAPER_YAML = ROOT / 'config/params/catapult_paper.yaml'       # the papers' catapult world
NODES = {'ship_motion_node': 'ShipMotionNode', 'master_ins_node': 'MasterInsNode',
         'slave_ins_node': 'SlaveInsNode', 'ldv_node': 'LdvNode',
         'alignment_filter_node': 'AlignmentFilterNode', 'air_data_node': 'AirDataNode',
         'air_data_filter_node': 'AirDataFilterNode'}
ARM = [60.0, -15.0, 20.0]


@pytest.fixture
def make_node():
    """make_node(name, *ros_args): the project's node `name` built with the papers' catapult params
    file (its lever arm exact: the filter's follows the aircraft's) and ros_args (`-p KEY:=VALUE`
    ...), as start_node.sh would start it."""
    dom = domain.claim()
    made = []

    def make(name: str, *ros_args: str):
        argv = ['test', '--ros-args', '--params-file', str(PAPER_YAML), *ros_args]
        rclpy.try_shutdown()                    # one node per context
        rclpy.init(args=argv, domain_id=dom)
        made.append(True)
        cls = getattr(importlib.import_module(f'{name}.node'), NODES[name])
        old, sys.argv = sys.argv, argv          # the node reads its -p rules from the command line
        try:
            return cls()
        finally:
            sys.argv = old
    yield make
    if made:
        rclpy.try_shutdown()
    domain.release(dom)


def _declared_scenario_keys(node) -> set[str]:
    return {n for n in node.list_parameters([], 0).names if n in params.SCENARIO_KEYS}


def _flat(sc) -> dict:
    return params.flat_scenario(sc)


# ---- what each node declares ------------------------------------------------------------

FILTER_EXTRA = {'rate_hz', 'ship.lat_deg', 'ship.lon_deg', 'aircraft.lever_arm_m', 'aircraft.heading_on_deck_deg',
                'seed', 'aircraft.lever_arm_survey_sigma_m',     # these two: to draw the survey error
                'ldv.mode'}                                      # the LDV installed: vector or beam


def test_filter_node_declares_filter_and_what_a_user_knows(make_node):
    node = make_node('alignment_filter_node')
    keys = _declared_scenario_keys(node)
    want = {f'filter.{f.name}' for f in dataclasses.fields(FilterConfig)} | FILTER_EXTRA
    assert keys == want
    # no simulation section: nothing of the ship's motion, the aircraft's truth or the sensors
    assert not [k for k in keys if k.split('.')[0] in ('master', 'imu', 'ldv', 'doppler', 'duration_s')
                and k not in FILTER_EXTRA]
    assert not [k for k in keys if k.startswith(('ship.', 'aircraft.')) and k not in FILTER_EXTRA]


@pytest.mark.parametrize('name,sections', [
    ('ship_motion_node', {'ship', 'name', 'seed', 'duration_s', 'rate_hz', 'start_time_s'}),
    ('master_ins_node', {'master', 'seed', 'rate_hz', 'start_time_s'}),
    ('slave_ins_node', {'aircraft', 'imu', 'reference_ins', 'seed', 'rate_hz', 'start_time_s'}),
    ('air_data_node', {'fads', 'seed', 'rate_hz', 'start_time_s'}),
    ('ldv_node', {'ldv', 'doppler', 'seed', 'rate_hz', 'start_time_s'}),
])
def test_simulation_nodes_declare_their_sections(make_node, name, sections):
    node = make_node(name)
    keys = _declared_scenario_keys(node)
    whole = {k for k in params.SCENARIO_KEYS if k.split('.')[0] in sections}
    assert whole <= keys
    extra = keys - whole
    if name == 'ship_motion_node':   # the streams' timing, for its run-out past the end
        assert extra == set(params.RUN_OUT)
    elif name == 'ldv_node':      # the origin, and the deck spot and catapult its defaults follow
        assert extra == ({'ship.lat_deg', 'ship.lon_deg', 'aircraft.lever_arm_m', 'aircraft.heading_on_deck_deg'}
                         | {k for k in params.SCENARIO_KEYS if k.startswith('aircraft.catapult.')})
    else:                         # the tangent plane's origin only
        assert extra == {'ship.lat_deg', 'ship.lon_deg'}
    assert len(keys) < len(params.SCENARIO_KEYS) / 2


def test_every_scenario_key_has_a_reader():
    read = {k for k in params.SCENARIO_KEYS for s in params.NODE_SCOPES.values() if s.covers(k)}
    assert params.SCENARIO_KEYS - read == {'description'}


def test_descriptors_carry_type_description_choices_and_bounds(make_node):
    node = make_node('alignment_filter_node')
    d = {p: node.describe_parameter(p) for p in ('filter.ldv_sigma_mps', 'filter.model', 'rate_hz',
                                                 'filter.lever_arm_m', 'aircraft.lever_arm_m')}
    assert d['filter.ldv_sigma_mps'].type == ParameterType.PARAMETER_DOUBLE
    assert '[m/s]' in d['filter.ldv_sigma_mps'].description
    assert d['filter.model'].type == ParameterType.PARAMETER_STRING
    assert 'vm15' in d['filter.model'].additional_constraints
    assert d['rate_hz'].floating_point_range[0].to_value == 2000.0
    assert d['filter.lever_arm_m'].type == ParameterType.PARAMETER_DOUBLE_ARRAY
    assert 'aircraft.lever_arm_m' in d['filter.lever_arm_m'].description
    assert 'filter.lever_arm_m' in d['aircraft.lever_arm_m'].description
    assert all(node.describe_parameter(k).description for k in _declared_scenario_keys(node))


# ---- one resolver for both paths --------------------------------------------------------

def test_node_lever_arm_follows_as_with_set(make_node):
    """-p aircraft.lever_arm_m on a node over a params file = --set on the command line:
    the filter's arm and the LDV's origin follow, unless given themselves."""
    arm = '[' + ','.join(repr(x) for x in ARM) + ']'
    sets = scenario.load('catapult_paper', {'aircraft.lever_arm_m': ARM})
    assert sets.filter.lever_arm_m == tuple(ARM) and sets.ldv.origin_m == tuple(ARM)
    for name in ('alignment_filter_node', 'ldv_node', 'slave_ins_node'):
        node = make_node(name, '-p', f'aircraft.lever_arm_m:={arm}')
        scope = params.NODE_SCOPES[name]
        want = {k: v for k, v in _flat(sets).items() if scope.covers(k)}
        have = {k: node.get_parameter(k).value for k in want}
        assert have == want, name
    node = make_node('alignment_filter_node', '-p', f'aircraft.lever_arm_m:={arm}',
                     '-p', 'filter.lever_arm_m:=[1.0,2.0,3.0]')
    assert node.sc.filter.lever_arm_m == (1.0, 2.0, 3.0)
    assert scenario.load('catapult_paper', {'aircraft.lever_arm_m': ARM, 'filter.lever_arm_m': [1.0, 2.0, 3.0]}
                         ).filter.lever_arm_m == (1.0, 2.0, 3.0)


@pytest.mark.parametrize('sets', [
    {},
    {'aircraft.lever_arm_m': ARM},
    {'aircraft.heading_on_deck_deg': 2.0, 'aircraft.catapult.accel_g': 3.0},
    {'imu.preset': 'mems_store', 'master.preset': 'ship_medium', 'seed': 9},
    {'aircraft.lever_arm_survey_sigma_m': 0.05, 'seed': 3},
    {'aircraft.lever_arm_m': ARM, 'ldv.origin_m': [0.0, 0.0, 0.0], 'doppler.enabled': True,
     'filter.model': 'seed001_13'},
])
def test_run_graph_params_resolve_in_every_node_to_the_set_scenario(tmp_path, sets):
    """The params file run_graph writes for `--set` holds only what was given; each node's
    resolution of it is the --set scenario on the node's keys."""
    given = scenario.given_data('catapult_paper', sets)
    sc = scenario.resolve(given)
    path = tmp_path / 'params.yaml'
    path.write_text(params_yaml(given, sc))
    on_file = params.params_file_given(path, 'any_node')
    assert 'filter.lever_arm_m' not in on_file or 'filter.lever_arm_m' in sets
    want = _flat(scenario.load('catapult_paper', sets))
    for name, scope in params.NODE_SCOPES.items():
        node_sc = params.node_scenario(on_file, scope)
        have = {k: v for k, v in _flat(node_sc).items() if scope.covers(k)}
        assert have == {k: v for k, v in want.items() if scope.covers(k)}, name


@pytest.mark.parametrize('path, name', [(GRAPH_YAML, 'catapult'), (PAPER_YAML, 'catapult_paper')])
def test_params_files_are_their_scenarios_as_given(path, name):
    on_disk = params.params_file_given(path, 'alignment_filter_node')
    given = scenario.given_data(name)
    assert on_disk == params.given_parameters(given, scenario.resolve(given))
    assert 'filter.lever_arm_m' not in on_disk and 'aircraft.lever_arm_m' in on_disk


def test_a_node_checks_only_what_its_keys_allow():
    """seed001_13 matches the Doppler radar: the whole scenario needs doppler.enabled, the
    filter node (which reads no doppler section) does not."""
    with pytest.raises(ConfigError, match='doppler.enabled'):
        scenario.load('catapult_paper', {'filter.model': 'seed001_13'})
    sc = params.node_scenario({'filter.model': 'seed001_13'}, params.NODE_SCOPES['alignment_filter_node'])
    assert sc.filter.model == 'seed001_13'


# ---- refusals ---------------------------------------------------------------------------

def test_unknown_parameter_is_refused(make_node):
    node = make_node('alignment_filter_node', '-p', 'filter.no_such_key:=1.0')
    with pytest.raises(ConfigError, match=r'alignment_filter_node: unknown parameter\(s\): filter\.no_such_key$'):
        params.refuse_unknown(node, ['x', '--ros-args', '-p', 'filter.no_such_key:=1.0'])


def test_misspelt_parameter_is_refused_with_the_likely_name(make_node):
    node = make_node('ldv_node', '-p', 'ldv.noise_mp:=0.1')
    with pytest.raises(ConfigError, match=r'ldv\.noise_mp \(did you mean ldv\.noise_mps\?\)'):
        params.refuse_unknown(node, [])


def test_other_nodes_scenario_keys_are_not_refused(make_node):
    """The default params file gives every node the whole scenario: the filter ignores ship.*."""
    node = make_node('alignment_filter_node', '-p', 'ship.sea_state:=5')
    params.refuse_unknown(node, [])
    assert not node.has_parameter('ship.sea_state')


def test_wrong_type_over_the_params_file_is_refused(make_node):
    # rcl keeps the params file's 0.01 when a -p value has another type: the node must look at -p
    with pytest.raises(ConfigError, match=r"^filter\.ldv_sigma_mps: expected a number, got 'abc'$"):
        make_node('alignment_filter_node', '-p', 'filter.ldv_sigma_mps:=abc')


def test_wrong_type_is_refused(make_node):
    with pytest.raises(ConfigError, match=r"^filter\.stf_rho: expected a number, got 'abc'$"):
        make_node('alignment_filter_node', '-p', 'filter.stf_rho:=abc')     # not in the params file
    with pytest.raises(ConfigError, match=r"^ship\.sea_state: expected an integer, got 4\.5$"):
        make_node('ship_motion_node', '-p', 'ship.sea_state:=4.5')


def test_integer_for_a_float_key_is_accepted(make_node):
    node = make_node('alignment_filter_node', '-p', 'filter.ldv_sigma_mps:=1')
    assert node.get_parameter('filter.ldv_sigma_mps').value == 1.0
    assert node.sc.filter.ldv_sigma_mps == 1.0


# ---- reading -p rules -------------------------------------------------------------------

def test_command_line_rules():
    argv = ['exe', 'arg', '--ros-args', '-p', 'seed:=5', '--param', 'filter.model:=vm12', '-r', 'a:=b',
            '-p', 'ldv_node:ldv.noise_mps:=0.5', '-p', '/other_node:ldv.bias_mps:=1.0', '--', '-p', 'x:=1']
    assert params.command_line_parameters(argv, 'ldv_node') == {
        'seed': '5', 'filter.model': 'vm12', 'ldv.noise_mps': '0.5'}


@pytest.mark.parametrize('text,value', [('5', 5), ('0x10', 16), ('1e-3', 1e-3), ('0.5', 0.5), ('true', True),
                                        ('off', False), ('abc', 'abc'), ("'5'", '5'), ('[1.0, 2.0]', [1.0, 2.0]),
                                        ('[1e-3, 2.5e2]', [1e-3, 250.0]), ('["a:1","b:2"]', ['a:1', 'b:2'])])
def test_rule_values_typed_as_rcl_types_them(text, value):
    got = params.ros_value(text)
    assert got == value and type(got) is type(value)
