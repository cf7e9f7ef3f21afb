"""bench/dds_cost.py: the transport's CPU over a run's messages, summed by hand."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / 'bench'))
import dds_cost  # noqa: E402


def test_the_transport_bound_sums_each_message_once_sent_and_once_per_reader():
    cost = {'a_us': 30.0, 'b_us': 5.0, 'c_us': 20.0}
    topics = {'/ship/odom': 1000, '/clock': 1000, '/other': 10}
    got = dds_cost.transport_bound(cost, topics, sim_time_s=60.0, cpus=2,
                                   readers={'/ship/odom': 4, '/clock': 1})
    # 1000 (30 + 25 * 4) + 1000 (30 + 25) + 10 (30 + 25): the topic not listed has the recorder only
    cpu_s = (1000 * 130.0 + 1000 * 55.0 + 10 * 55.0) * 1e-6
    assert got['transport_cpu_s'] == pytest.approx(cpu_s, rel=1e-12)
    assert got['reads'] == 4000 + 1000 + 10 and got['messages'] == 2010
    assert got['rtf_bound'] == pytest.approx(60.0 / (cpu_s / 2), rel=1e-12)


def test_the_graph_readers_count_the_recorder_and_every_subscribing_node():
    """docs/architecture.md: /ship/odom goes to the master, slave and LDV nodes, /aircraft/imu to the
    filter; the recorder takes every topic (so one reader is the least a topic has)."""
    from alignment_ros.graph import MATCHED
    readers = dds_cost.readers_per_topic()
    assert readers['/ship/odom'] == 4 and readers['/aircraft/imu'] == 2
    assert all('recorder' in names for sent in MATCHED.values() for names in sent.values())


def test_a_process_that_reports_and_then_hangs_is_stopped_and_its_report_kept(tmp_path):
    """A role process can hang in its DDS teardown after it printed its result (a publish was
    lost that way): the parent stops it after the timeout and keeps the line; one that printed
    nothing gives None."""
    import subprocess
    import sys
    import time
    mark = tmp_path / 'reported'
    hang = subprocess.Popen([sys.executable, '-c', 'import json, pathlib, sys, time; '
                             'print(json.dumps({"taken": 3}), flush=True); pathlib.Path(sys.argv[1]).touch(); '
                             'time.sleep(60)', str(mark)], stdout=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 30.0
    while not mark.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert dds_cost._result(hang, 0.5) == ({'taken': 3}, True, '')
    failed = subprocess.Popen([sys.executable, '-c', 'import sys; sys.exit("not acknowledged")'],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert dds_cost._result(failed, 10.0) == (None, False, 'not acknowledged\n')


def test_a_failed_setting_is_run_again_and_its_failures_kept(monkeypatch):
    calls = []

    def flaky(messages, readers):
        calls.append(readers)
        if len(calls) < dds_cost.ATTEMPTS:
            raise RuntimeError('1 of 2 subscribers reported nothing')
        return 10.0, [15.0, 16.0], 1
    monkeypatch.setattr(dds_cost, 'one_setting', flaky)
    failures: list[str] = []
    assert dds_cost._setting(100, 2, failures) == (10.0, [15.0, 16.0], 1)
    assert failures == ['2 readers: 1 of 2 subscribers reported nothing'] * (dds_cost.ATTEMPTS - 1)

    def always_fails(messages, readers):
        raise RuntimeError('never')
    monkeypatch.setattr(dds_cost, 'one_setting', always_fails)
    with pytest.raises(RuntimeError, match='never'):
        dds_cost._setting(100, 2, failures)
