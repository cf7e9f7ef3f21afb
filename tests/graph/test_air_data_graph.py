"""The two air-data scenarios through the graph, short: a complete run, air-data estimates equal
to the batch estimator's at the same stamps, and a filter node that never reads a truth topic."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import deserialize_message

from alignment_core import air_data_run
from alignment_core.config import scenario
from alignment_ros import topics
from alignment_ros.air_data_convert import msg_to_labelled
from alignment_ros.bag import read_bag
from alignment_ros.convert import to_ns
from alignment_ros.topics import msg_class

ROOT = Path(__file__).resolve().parents[2]
CASES = {'seed004': ['duration_s=20.0'],
         'carrier_flight': ['duration_s=72.0', 'aircraft.catapult.launch_time_s=55.0']}


def graph_estimates(bag: Path) -> dict[int, np.ndarray]:
    """stamp -> /air_data/state values, paired with /air_data/velocity (published together)."""
    states, stamps, labels = [], [], None
    for m in read_bag(bag, (topics.AIR_DATA_STATE, topics.AIR_DATA_VELOCITY)):
        msg = deserialize_message(m.data, msg_class(m.type_name))
        if m.topic == topics.AIR_DATA_STATE:
            _, labels, data = msg_to_labelled(msg)
            states.append(data[0])
        else:
            stamps.append(to_ns(msg.header.stamp))
    assert labels is not None and len(states) == len(stamps)
    return {t: s for t, s in zip(stamps, states)}, labels


@pytest.mark.parametrize('name', sorted(CASES))
def test_air_data_scenario_through_the_graph(tmp_path, name):
    out = tmp_path / name
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', name, '--out', str(out), '--real-time-factor', '5']
    for s in CASES[name]:
        cmd += ['--set', s]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    assert 'lost messages: 0' in p.stdout and 'air data:' in p.stdout
    stats = json.loads((out / 'stats' / 'air_data_filter_node.json').read_text())
    assert not [t for t in stats['received'] if t.startswith('/truth')], stats['received']
    assert stats['air_data']['failure'] == '' and stats['air_data']['updates'] > 10
    est, labels = graph_estimates(out / 'bag')
    assert all(np.all(np.isfinite(v)) for v in est.values())
    sc = scenario.load(name, scenario.parse_overrides(CASES[name]))
    run = air_data_run.estimate(sc, air_data_run.simulate(sc))
    batch = {int(round(t * 1e9)) + sc.t0_ns: v for t, v in zip(run.t, run.value)}
    common = sorted(set(est) & set(batch))
    assert len(common) == len(est) == len(batch)
    for n in ('mach', 'alpha_rad', 'beta_rad', 'wind_east_mps'):
        g = np.array([est[t][labels.index(n)] for t in common])
        b = np.array([batch[t][list(run.labels).index(n)] for t in common])
        np.testing.assert_allclose(g, b, rtol=0, atol=1e-9 * max(1.0, float(np.max(np.abs(b)))), err_msg=n)
