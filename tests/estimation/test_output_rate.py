"""filter.output_rate_hz: the engine emits at master stamps, the first at the first master sample,
then one at the first master stamp at or after each further multiple of 1 / output_rate_hz."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario

CATAPULT = {'duration_s': 6.0, 'aircraft.catapult.launch_time_s': 3.0}


@pytest.fixture(scope='module')
def inputs():
    return pipeline.simulate(scenario.load('catapult_paper', CATAPULT))


def _stamps(rate_hz: float, inp) -> np.ndarray:
    sc = scenario.load('catapult_paper', {**CATAPULT, 'filter.output_rate_hz': rate_hz})
    return np.array([e.t_ns for e in pipeline.align(sc, inp).outputs], dtype=np.int64)


@pytest.mark.parametrize('rate_hz', [2.0, 25.0])
def test_outputs_on_the_master_grid_are_one_period_apart(rate_hz, inputs):
    """100 Hz master: 2 Hz and 25 Hz are every 50th and every 4th master sample."""
    t = _stamps(rate_hz, inputs)
    master = np.array([m.t_ns for m in inputs.master], dtype=np.int64)
    assert t[0] == master[0]
    assert np.all(np.diff(t) == round(1e9 / rate_hz))
    assert len(t) == int((master[-1] - master[0]) * rate_hz // 1e9) + 1


def test_an_off_grid_rate_takes_the_next_master_stamp(inputs):
    """30 Hz on a 10 ms grid: output k at the first master stamp at or after t0 + k / 30 s
    (spacings of 30 and 40 ms, on average 1/30 s)."""
    t = _stamps(30.0, inputs)
    master = np.array([m.t_ns for m in inputs.master], dtype=np.int64)
    due = master[0] + np.round(np.arange(len(t)) * 1e9 / 30.0).astype(np.int64)
    want = master[np.searchsorted(master, due)]
    assert np.array_equal(t, want)
    assert set(np.diff(t)) == {30_000_000, 40_000_000}
    assert master[-1] - t[-1] < 1e9 / 30.0


def test_an_output_rate_above_the_master_rate_emits_at_every_master_sample(inputs):
    t = _stamps(250.0, inputs)
    assert np.array_equal(t, [m.t_ns for m in inputs.master])
