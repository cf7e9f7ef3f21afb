"""A master INS with a latency and a transport jitter at 50 Hz (its stamps off the end's grid):
the graph simulates its run-out past the end (alignment_core/run_out.py), so the run and its
replay finish complete, and the graph gives the batch's estimates at every batch stamp (all up
to the end); what comes after the end is the run-out's."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from alignment_core import pipeline, run_out
from alignment_core.config import scenario
from alignment_ros.summary import estimates_from_bag

ROOT = Path(__file__).resolve().parents[2]
SETS = ['duration_s=4.0', 'seed=5', 'master.rate_hz=50.0', 'master.latency_s=0.03', 'master.latency_jitter_s=0.015',
        'filter.master_latency_s=0.03']


@pytest.fixture(scope='module')
def graph_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp('run_out') / 'run'
    cmd = [str(ROOT / 'scripts/run_graph.sh'), '--scenario', 'deck_paper', '--out', str(out), '--real-time-factor', '0',
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
