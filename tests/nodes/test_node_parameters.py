"""Started nodes (scripts/start_node.sh with the default params file) refuse an unknown or
wrong-typed parameter at start-up with one line naming it, and resolve `-p` keys as `--set`
does: the filter's lever arm follows `aircraft.lever_arm_m`."""
from __future__ import annotations

import pytest
from rcl_interfaces.srv import GetParameters
from support.ros_driving import spin_until

NODES = ('ship_motion_node', 'master_ins_node', 'slave_ins_node', 'ldv_node', 'alignment_filter_node',
         'air_data_node', 'air_data_filter_node')


def _refusal(p) -> list[str]:
    out, _ = p.communicate(timeout=60)
    assert p.returncode == 2, out
    assert 'Traceback' not in out
    return [line for line in out.splitlines() if line.strip()]


@pytest.mark.parametrize('name', NODES)
def test_unknown_parameter_refused_by_every_node(ros, name):
    _, start = ros
    lines = _refusal(start(name, '-p', 'filter.no_such_key:=1.0'))
    assert lines == [f'invalid configuration: {name}: unknown parameter(s): filter.no_such_key']


def test_wrong_type_refused_over_the_params_file(ros):
    _, start = ros
    lines = _refusal(start('alignment_filter_node', '-p', 'filter.ldv_sigma_mps:=abc'))
    assert lines == ["invalid configuration: filter.ldv_sigma_mps: expected a number, got 'abc'"]


def test_filter_lever_arm_follows_the_deck_spot(ros):
    node, start = ros
    start('alignment_filter_node', '-p', 'aircraft.lever_arm_m:=[60.0,-15.0,20.0]')
    cli = node.create_client(GetParameters, '/alignment_filter_node/get_parameters')
    assert cli.wait_for_service(timeout_sec=30)
    fut = cli.call_async(GetParameters.Request(names=['filter.lever_arm_m', 'filter.heading_on_deck_deg']))
    spin_until(node, fut.done)
    arm, heading = fut.result().values
    assert list(arm.double_array_value) == [60.0, -15.0, 20.0]
    assert heading.double_value == 0.0
