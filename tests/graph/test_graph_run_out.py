"""The default `deck` through the graph (the carrier as it is: MMG ship in an irregular sea, the
aircraft on its gear, deck flexure, a beam LDV, a Schuler master INS at 50 Hz with a latency and
a transport jitter not told to the filter, a lever-arm survey error; the delay, lever-arm states
and the reference specific force in the filter). The master's stamps fall off the end's grid:
the graph simulates its run-out past the end (alignment_core/run_out.py), so the run and its
replay finish complete, and the graph gives the batch's estimates at every batch stamp (all up
to the end), the slave attitude at its own IMU time included; what comes after the end is the
run-out's."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from alignment_core import pipeline, run_out
from alignment_core.config import scenario
from alignment_ros.convert import to_ns
from alignment_ros.summary import _read, estimates_from_bag
from alignment_ros.topics import ALIGN_ATTITUDE

ROOT = Path(__file__).resolve().parents[2]


def attitudes_from_bag(bag: Path) -> dict[str, np.ndarray]:
    msgs = _read(bag, (ALIGN_ATTITUDE,))[ALIGN_ATTITUDE]
    q = [[m.pose.pose.orientation.x, m.pose.pose.orientation.y, m.pose.pose.orientation.z,
          m.pose.pose.orientation.w] for m in msgs]
    return {'t_ns': np.array([to_ns(m.header.stamp) for m in msgs], dtype=np.int64), 'q': np.array(q)}
SETS = ['duration_s=4.0', 'seed=5']


@pytest.fixture(scope='module')
def graph_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp('run_out') / 'run'
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'deck', '--out', str(out), '--real-time-factor', '0',
           '--timeout', '900', '--no-plots']
    for s in SETS:
        cmd += ['--set', s]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=1000)
    assert p.returncode == 0, p.stdout + p.stderr
    assert 'lost messages: 0' in p.stdout and 'complete: yes' in p.stdout
    return out


def test_latency_run_completes_and_equals_the_batch(graph_run):
    sc = scenario.load(str(graph_run / 'scenario.yaml'))
    assert run_out.run_out_samples(sc) > 0
    end = run_out.end_ns(sc)
    batch = pipeline.run(sc, keep_truth=False)
    t_b = np.array([x.t_ns for x in batch.estimates], dtype=np.int64)
    mu_b = np.array([x.misalignment for x in batch.estimates])
    sig_b = np.array([x.misalignment_sigma for x in batch.estimates])
    assert t_b[-1] < end                  # the batch ends short of the end: the graph must not wait for it
    e = estimates_from_bag(graph_run / 'bag')
    k = len(t_b)
    assert np.array_equal(e['t_ns'][:k], t_b)
    assert np.max(np.abs(e['misalignment'][:k] - mu_b)) < 1e-9
    np.testing.assert_allclose(e['sigma'][:k], sig_b, rtol=1e-9)
    assert e['t_ns'][k] >= end and np.all(e['t_ns'][k:] > t_b[-1])   # the run-out reached the end
    att = attitudes_from_bag(graph_run / 'bag')
    nav_b = np.array([x.navigation_ns for x in batch.estimates], dtype=np.int64)
    assert np.count_nonzero(nav_b != t_b) > k // 2                    # the INS's own time, off the stamps
    assert np.array_equal(att['t_ns'][:k], nav_b)
    q_b = np.array([x.q_nb for x in batch.estimates])
    assert np.max(np.abs(np.abs(np.sum(att['q'][:k] * q_b, axis=1)) - 1.0)) < 1e-12
    s = json.loads((graph_run / 'summary.json').read_text())
    assert s['complete'] is True and s['lost_total'] == 0 and s['sim_time_s'] == sc.duration_s


def test_replay_of_a_latency_run_finishes(graph_run, tmp_path):
    out = tmp_path / 'replay'
    p = subprocess.run([str(ROOT / 'scripts/replay.sh'), str(graph_run), '--out', str(out), '--no-plots'],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    assert 'complete: yes' in p.stdout
    g, r = estimates_from_bag(graph_run / 'bag'), estimates_from_bag(out / 'bag')
    end = run_out.end_ns(scenario.load(str(graph_run / 'scenario.yaml')))
    k = int(np.searchsorted(g['t_ns'], end, side='right'))
    assert np.array_equal(r['t_ns'][:k], g['t_ns'][:k])
    assert np.max(np.abs(r['misalignment'][:k] - g['misalignment'][:k])) < 1e-12
