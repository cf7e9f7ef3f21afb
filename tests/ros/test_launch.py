"""The launcher's bookkeeping (alignment_ros.launch, signals): which publishers are foreign, exit
statuses, a signal that arrives while a process is being started, impossible option values."""
from __future__ import annotations

import argparse
import json
import os
import signal

import pytest

from alignment_ros.launch import Run, number_type
from alignment_ros.signals import Interrupted, SignalGuard


def run_with(tmp_path, publishers: dict) -> Run:
    (tmp_path / 'stats').mkdir()
    (tmp_path / 'stats' / 'recorder.json').write_text(json.dumps({'publishers': publishers}))
    return Run('test', tmp_path, SignalGuard())


def test_foreign_publishers_are_other_nodes_or_a_second_one_of_ours(tmp_path):
    run = run_with(tmp_path, {
        '/ship/odom': {'/ship_motion_node': 1},
        '/clock': {'/ship_motion_node': 2},                   # a leftover ship of another run
        '/aircraft/imu': {'/slave_ins_node': 1, '/talker': 1},
        '/master/odom': {'/_NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_': 1},   # never named
    })
    ours = {'ship_motion_node', 'slave_ins_node', 'master_ins_node'}
    assert run.foreign_publishers(ours) == {
        '/clock': ['/ship_motion_node'], '/aircraft/imu': ['/talker'],
        '/master/odom': ['/_NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_']}


def test_exit_status(tmp_path):
    run = run_with(tmp_path, {})
    assert run.exit_code(True) == 0
    assert run.exit_code(False) == 1
    run.failure = 'the recorder ended before the end time'
    assert run.exit_code(True) == 1
    run.interrupted = Interrupted(signal.SIGTERM)
    assert run.exit_code(False) == 143 and Interrupted(signal.SIGINT).exit_code == 130


def test_a_signal_while_starting_a_process_waits_until_it_is_registered():
    started = []
    before = signal.getsignal(signal.SIGINT)        # default_int_handler, or SIG_IGN when started in the background
    with SignalGuard() as guard:
        with pytest.raises(Interrupted) as e:
            with guard.deferred():
                os.kill(os.getpid(), signal.SIGINT)
                started.append('registered')        # still runs: the signal is deferred
        assert e.value.signum == signal.SIGINT and started == ['registered']
        os.kill(os.getpid(), signal.SIGTERM)        # later ones: the run is stopping already
    assert signal.getsignal(signal.SIGINT) is before               # restored, whatever it was


@pytest.mark.parametrize('text, ok', [('0', True), ('2.5', True), ('-1', False), ('nan', False),
                                      ('inf', False), ('x', False)])
def test_non_negative_finite_numbers(text, ok):
    parse = number_type(0.0)
    if ok:
        assert parse(text) == float(text)
    else:
        with pytest.raises(argparse.ArgumentTypeError):
            parse(text)


@pytest.mark.parametrize('scenario', ['catapult_paper', 'seed004'])
def test_the_end_of_a_run_is_judged_on_stamped_topics_only(scenario):
    """An unstamped topic is logged at the recorder's latest /clock, which under load lags the
    other streams: its last message can be logged before the end time, and the run would wait
    for an end that never comes (seen in CI with /air_data/state)."""
    from alignment_core.config import scenario as core_scenario
    from alignment_ros import msg_definitions
    from alignment_ros.graph import end_topics_of
    from alignment_ros.topics import TOPIC_TYPES
    sc = core_scenario.resolve(core_scenario.given_data(scenario, {}, None))
    unstamped = [t for t in end_topics_of(sc) if not msg_definitions.has_stamp(TOPIC_TYPES[t])]
    assert unstamped == []


def test_the_launcher_starts_its_nodes_without_use_sim_time(tmp_path, monkeypatch):
    """The nodes never read ROS time (rclpy's /clock reader cost each node CPU on every ship
    sample): neither a forked node's command line nor start_node.sh's sets use_sim_time."""
    from alignment_ros import graph
    (tmp_path / 'logs').mkdir()
    run = run_with(tmp_path, {})
    seen: dict[str, list[str]] = {}
    monkeypatch.setattr(Run, 'fork', lambda self, name, entry, argv, log: seen.setdefault('fork', argv))
    monkeypatch.setattr(Run, 'spawn', lambda self, name, cmd, **kw: seen.setdefault('spawn', cmd))
    for fork in (True, False):
        graph.start(run, 'master_ins_node', tmp_path / 'params.yaml', fork=fork)
    assert set(seen) == {'fork', 'spawn'}
    assert not any('use_sim_time' in a for argv in seen.values() for a in argv)
    script = (graph.root() / 'scripts' / 'start_node.sh').read_text()
    assert 'use_sim_time' not in script.split('\nset -euo pipefail')[1]       # its commands, not its comments
