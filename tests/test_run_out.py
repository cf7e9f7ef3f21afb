"""The run-out (alignment_core/run_out.py): a graph's filter, which never flushes, reaches the
scenario's end once the simulation runs on for the run-out, and gives the batch's outputs up to
the end. The graph is emulated in-process: the batch's inputs for the longer simulation, fed in
the nodes' order, without the batch's final flush."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alignment_core import pipeline, run_out
from alignment_core.config import scenario

CASES = {
    'latency 30 ms': ['master.latency_s=0.03'],
    'latency + jitter at 50 Hz': ['master.rate_hz=50.0', 'master.latency_s=0.03', 'master.latency_jitter_s=0.015'],
    '50 Hz, odd sample count': ['master.rate_hz=50.0', 'duration_s=3.01'],
    'LDV latency and rate': ['ldv.rate_hz=25.0', 'ldv.latency_s=0.02'],
}


def _scenario(sets: list[str]) -> scenario.Scenario:
    given = scenario.given_data('deck_paper', scenario.parse_overrides(['duration_s=3.0', 'seed=3', *sets]), None)
    return scenario.resolve(given)


def _graph_stamps(sc: scenario.Scenario, extra: int) -> tuple[np.ndarray, np.ndarray]:
    """Output stamps and misalignments of a graph simulating `extra` samples past the end."""
    longer = dataclasses.replace(sc, duration_s=sc.duration_s + extra / sc.rate_hz)
    filt = pipeline.align(longer, pipeline.simulate(longer), final=False)
    return (np.array([e.t_ns for e in filt.outputs], dtype=np.int64),
            np.array([e.misalignment for e in filt.outputs]))


def test_default_scenarios_need_no_run_out():
    assert run_out.run_out_samples(scenario.resolve(scenario.given_data('catapult_paper', {}, None))) == 0
    assert run_out.run_out_samples(_scenario(['master.rate_hz=50.0'])) == 0


@pytest.mark.parametrize('name', sorted(CASES))
def test_run_out_reaches_the_end_and_keeps_the_batch(name):
    sc = _scenario(CASES[name])
    end = run_out.end_ns(sc)
    assert end == sc.t0_ns + round(sc.duration_s * 1e9)
    n = run_out.run_out_samples(sc)
    assert n > 0
    t_short, _ = _graph_stamps(sc, 0)
    assert t_short[-1] < end                 # without it, the graph's outputs fall short (the hang)
    t, mu = _graph_stamps(sc, n)
    assert t[-1] >= end
    batch = pipeline.run(sc, keep_truth=False)
    t_b = np.array([e.t_ns for e in batch.estimates], dtype=np.int64)
    mu_b = np.array([e.misalignment for e in batch.estimates])
    assert t_b[-1] <= end
    k = len(t_b)
    assert np.array_equal(t[:k], t_b)           # the batch's outputs are the graph's up to the end
    assert np.array_equal(mu[:k], mu_b)
    assert np.all(t[k:] > end)
