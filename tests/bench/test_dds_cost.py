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
