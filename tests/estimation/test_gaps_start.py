"""The start of a run with a told master latency (estimation/imu_events.py, docs/engine.md,
initialisation): the first master sample is valid at its stamp less the latency, which can lie
before the IMU's data begins (its first sample covers (t0 - dt, t0]). Where the slave's first
step would then be longer than the bridge limit, it is no IMU gap: the IMU stream has none. The
slave starts at the first master valid where the IMU's data begins; nothing is bridged, flagged
'gap' or unmatched. It used to be bridged as a gap ('gap' WARN, 4 master samples unmatched on
deck_paper with 50 ms told, where none is real)."""
from __future__ import annotations

import pytest
from support.engine_feed import feed_in_order

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.health import OK


def _flagged(f) -> list:
    """The outputs flagged 'gap', by the estimate or by its /diagnostics report."""
    return [e for e in f.outputs if 'gap' in e.flags or 'gap' in e.report.flags]


@pytest.mark.parametrize('told', [0.05, 0.2])
def test_a_told_latency_reaching_before_the_imu_data_is_no_gap(told):
    """deck_paper (no real latency, IMU from 1.01 s, master from 1.00 s at 100 Hz): the slave,
    initialised at 1.00 s - told before any IMU sample, starts again at the master sample valid
    at 1.00 s; the ones valid before it are skipped before initialisation."""
    sc = scenario.load('deck_paper', {'duration_s': 2.0, 'filter.master_latency_s': told}, seed=1)
    f = pipeline.align(sc, pipeline.simulate(sc))
    c = f.counters
    assert c.imu_gaps == 0 and c.bridged_gaps == 0 and c.unmatched_master == 0
    assert c.skipped_before_init == round(told * 100)         # valid from 1.00 s - told to 0.99 s (the
                                                              # first started the slave that was dropped)
    assert not _flagged(f)
    first = f.outputs[0]                                      # at 1.00 s, from the slave started too early
    assert first.level == OK and first.report.level == OK
    after = next(e for e in f.outputs if e.updates > 0)
    assert after.validity_ns >= 1_000_000_000                 # every match at or after the IMU's start


def test_a_told_latency_with_the_imu_already_started_is_no_long_first_step():
    """deck_paper with the master from 1.05 s and 100 ms told: the IMU's first samples are
    processed before the first master sample (valid at 0.95 s), and the slave used to be started
    there with one 60 ms strapdown step over the IMU samples replayed (counted as an IMU gap)."""
    sc = scenario.load('deck_paper', {'duration_s': 2.0, 'filter.master_latency_s': 0.1}, seed=1)
    inp = pipeline.simulate(sc)
    events = []
    for k in range(len(inp.ships)):
        if k > 0:
            events.append(('imu', inp.imu[k - 1]))
        events += [('ldv', inp.ldv[k])] + ([('master', inp.master[k])] if k >= 5 else [])
    f = feed_in_order(sc, events)
    c = f.counters
    assert c.imu_gaps == 0 and c.bridged_gaps == 0 and c.unmatched_master == 0
    assert c.skipped_before_init == 5 and not _flagged(f)      # valid at 0.95-0.99 s


def test_an_imu_that_starts_late_is_still_reported_while_it_is_silent():
    """deck_paper without latency, the IMU's first 0.3 s left out: the outputs before the IMU's
    data are flagged 'gap' by the age of the slave solution (the IMU is silent from the start);
    the slave then starts where the IMU's data begins, with nothing bridged."""
    sc = scenario.load('deck_paper', {'duration_s': 2.0}, seed=1)
    inp = pipeline.simulate(sc)
    events = []
    for k in range(len(inp.ships)):
        if k > 30:
            events.append(('imu', inp.imu[k - 1]))
        events += [('ldv', inp.ldv[k]), ('master', inp.master[k])]
    f = feed_in_order(sc, events)
    c = f.counters
    assert c.bridged_gaps == 0 and c.imu_gaps == 0 and c.unmatched_master == 0 and c.skipped_before_init > 0
    flagged = _flagged(f)
    assert flagged and all(e.t_ns < 1_310_000_000 for e in flagged)
    assert all(e.level == OK for e in f.outputs if e.t_ns >= 1_310_000_000)
