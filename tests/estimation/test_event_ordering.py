"""The filter's output depends on its inputs' contents, never on how the streams interleave;
bad inputs are rejected and counted without disturbing the rest."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from support.engine_feed import feed_in_order, random_interleaving

from alignment_core import pipeline
from alignment_core.config import scenario

SC = scenario.load('catapult_paper', {'duration_s': 6.0, 'aircraft.catapult.launch_time_s': 3.0})


@pytest.fixture(scope='module')
def inputs():
    return pipeline.simulate(SC)


def _events(inp):
    return ([('imu', s) for s in inp.imu], [('ldv', s) for s in inp.ldv], [('master', s) for s in inp.master])


def _outputs(f):
    return np.array([np.concatenate([e.misalignment, e.sigma, e.q_nb]) for e in f.outputs])


def test_random_interleavings_give_identical_outputs(inputs):
    ref = _outputs(pipeline.align(SC, inputs))
    rng = np.random.default_rng(3)
    for _ in range(3):
        out = _outputs(feed_in_order(SC, random_interleaving(inputs, rng)))
        assert np.array_equal(out, ref)


def test_nonfinite_and_out_of_order_inputs_are_rejected_and_counted(inputs):
    imu, ldv, master = _events(inputs)
    bad_imu = dataclasses.replace(inputs.imu[100], t_ns=inputs.imu[100].t_ns + 1,
                                  gyro=np.array([np.nan, 0.0, 0.0]))
    stale = inputs.master[50]
    events = imu[:200] + [('imu', bad_imu)] + imu[200:] + ldv + master[:300] + [('master', stale)] + master[300:]
    f = feed_in_order(SC, events)
    assert f.counters.rejected_nonfinite == 1
    assert f.counters.rejected_out_of_order == 1
    assert np.array_equal(_outputs(f), _outputs(pipeline.align(SC, inputs)))


def test_imu_gap_is_counted_and_the_filter_keeps_running(inputs):
    imu, ldv, master = _events(inputs)
    events = imu[:100] + imu[110:] + ldv + master
    f = feed_in_order(SC, events)
    assert f.counters.imu_gaps == 1
    assert len(f.outputs) == len(pipeline.align(SC, inputs).outputs)
    assert all(np.all(np.isfinite(e.misalignment)) for e in f.outputs)
