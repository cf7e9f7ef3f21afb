"""filter.gate_chi2 gates the master matches: an update whose normalised innovation squared
exceeds it is skipped and counted, so a few corrupted master samples cannot pull the estimate."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario

DECK = {'duration_s': 10.0}
BAD = range(500, 505)                 # five master samples at 5 s, each 0.5 m/s off along the bow


def _corrupted(inp):
    master = list(inp.master)
    for k in BAD:
        master[k] = dataclasses.replace(master[k], v_b=master[k].v_b + np.array([0.5, 0.0, 0.0]))
    return dataclasses.replace(inp, master=master)


def _offsets(gate: float):
    """Clean and corrupted engines, and the corrupted run's misalignment minus the clean run's,
    in units of the clean run's sigma, at each output from the first corrupted sample on."""
    sc = scenario.load('deck_paper', {**DECK, 'filter.gate_chi2': gate})
    inp = pipeline.simulate(sc)
    clean, bad = pipeline.align(sc, inp), pipeline.align(sc, _corrupted(inp))
    t_bad = inp.master[BAD[0]].t_ns
    d = np.array([(b.misalignment - a.misalignment) / a.misalignment_sigma
                  for a, b in zip(clean.outputs, bad.outputs, strict=True) if a.t_ns >= t_bad])
    return clean, bad, np.abs(d)


@pytest.fixture(scope='module')
def gated():
    return _offsets(25.0)


def test_gated_samples_are_skipped_and_counted(gated):
    """Parked, the match noise is sqrt(0.005^2 + 0.001^2) m/s per axis, so a 0.5 m/s error has a
    NIS of ~1e4; clean samples exceed 25 (chi-square, 3 dof) with probability 1.5e-5."""
    clean, bad, _ = gated
    assert clean.counters.gated == 0
    assert bad.counters.gated == len(BAD) and bad.counters.updates == clean.counters.updates - len(BAD)


def test_with_the_gate_the_estimate_stays_with_the_clean_run(gated):
    """The gated run lacks the information of 5 of the ~500 samples since the start, so it differs
    from the clean run by about sigma sqrt(5 / 500) = 0.1 sigma (one standard deviation): within
    half a sigma at every output from the corrupted samples on."""
    _, _, d = gated
    assert np.all(d < 0.5)


def test_without_the_gate_the_corrupted_samples_pull_the_estimate():
    clean, bad, d = _offsets(0.0)
    assert bad.counters.gated == 0 and bad.counters.updates == clean.counters.updates
    assert np.max(d) > 10.0 and np.max(d[-1]) > 10.0


def test_the_default_gate_is_on_and_never_gates_a_clean_run():
    """filter.gate_chi2 = 1e6 by default: a gross-outlier gate (a velocity innovation 1000 sigma
    off); the clean deck run's largest NIS is ~20 (chi2_3 over 1000 updates)."""
    sc = scenario.load('deck_paper', DECK)
    assert sc.filter.gate_chi2 == 1e6
    f = pipeline.align(sc, pipeline.simulate(sc))
    assert f.counters.gated == 0 and f.counters.gate_released == 0


def test_a_gated_run_is_released_after_gate_release_updates():
    """A master velocity 0.5 m/s off for 30 samples (NIS ~1e4 each) with the gate at 25: the
    first 10 are gated, the 11th is taken ungated (the filter would otherwise lock itself out if
    its state, not the data, were wrong), then the gate closes again on the next ones."""
    sc = scenario.load('deck_paper', {**DECK, 'filter.gate_chi2': 25.0})
    inp = pipeline.simulate(sc)
    master = list(inp.master)
    for k in range(500, 530):
        master[k] = dataclasses.replace(master[k], v_b=master[k].v_b + np.array([0.5, 0.0, 0.0]))
    f = pipeline.align(sc, dataclasses.replace(inp, master=master))
    assert f.counters.gate_released >= 1
    assert f.counters.gated + f.counters.updates == pipeline.align(sc, inp).counters.updates
