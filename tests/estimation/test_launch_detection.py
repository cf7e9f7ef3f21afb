"""Launch detection from the LDV: one noisy sample above `launch_detect_mps` is not a launch.

A 1 cm/s-per-axis LDV exceeds 5 cm/s in |v| with probability P(chi2_3 > 25) = 1.5e-5 per
sample, i.e. about once in 11 minutes at 100 Hz, and the old single-sample rule took such a
spike for the launch (3 of 50 catapult seeds: parked matching switched to moving minutes early,
the launch noise spent on the deck and 1.2-1.4' of pitch error under vibration). The engine now
needs `launch_confirm_samples` valid samples in a row."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.engine import TransferAlignment


def _run(sc, ldv):
    inp = pipeline.simulate(sc)
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)
    for k in range(len(inp.ships)):
        if k > 0:
            f.push_imu(inp.imu[k - 1])
        f.push_ldv(ldv(inp.ldv[k]))
        f.push_master(inp.master[k])
        f.process()
    f.process(final=True)
    return f, inp


def test_a_single_ldv_spike_on_the_parked_deck_is_not_a_launch():
    sc = scenario.load('deck', {'duration_s': 6.0})
    spike_ns = sc.t0_ns + 3_000_000_000

    def spiked(s):
        return replace(s, v_s=np.array([0.2, 0.0, 0.0])) if s.t_ns == spike_ns else s
    f, _ = _run(sc, spiked)
    assert not f.moving and f.t_launch is None
    assert f.counters.unmatched_master == 0 and f.counters.updates == 600     # 601 samples, the first initialises
    # the old rule (one sample) takes it for the launch
    old = replace(sc, filter=replace(sc.filter, launch_confirm_samples=1))
    f1, _ = _run(old, spiked)
    assert f1.moving and f1.t_launch == spike_ns


def test_the_catapult_launch_is_dated_at_its_first_sample():
    """Confirmation delays the decision by two samples, not the launch time: t_launch is the first
    LDV sample above the threshold, and the held samples are integrated into the deck displacement
    from it on (the trapezoids of every valid sample pair from the one before the first, which
    opens the stroke's first interval, to the last)."""
    sc = scenario.load('catapult', {'duration_s': 4.0, 'aircraft.catapult.launch_time_s': 2.0})
    f, inp = _run(sc, lambda s: s)
    first = next(s.t_ns for s in inp.ldv if s.valid and np.linalg.norm(s.v_s) > sc.filter.launch_detect_mps)
    assert f.t_launch == first
    k = next(i for i, s in enumerate(inp.ldv) if s.t_ns == first)
    v = inp.ldv[k - 1:]
    disp = np.zeros(3)
    for a, b in zip(v[:-1], v[1:]):
        if a.valid and b.valid:
            disp += 0.5 * (a.v_s + b.v_s) * (b.t_ns - a.t_ns) * 1e-9
    np.testing.assert_allclose(f.deck_disp, disp, rtol=1e-12, atol=1e-12)
    assert np.linalg.norm(disp) > 1.0


def test_hold_back_creep_is_deck_motion_but_not_the_launch():
    """inflight: the engines run up against the hold-back bar for 2 s before the 10 s launch and
    the airframe creeps 5 cm forward (up to ~4.5 cm/s, below the 5 cm/s launch threshold). A
    parked match would take that for a 9-sigma velocity error; the LDV median sees the creep and
    the aircraft counts as moving from then on, while the launch (the launch-noise window) is
    still dated at the stroke."""
    sc = scenario.load('inflight', {'duration_s': 12.0}, seed=3)
    f, _ = _run(sc, lambda s: s)
    hold = sc.t0_ns + 8_000_000_000
    launch = sc.t0_ns + 10_000_000_000
    assert f.counters.creep_detected == 1
    assert hold < f.t_moving < launch <= f.t_launch < launch + 100_000_000
    # a parked deck never creeps: the 1 cm/s LDV noise stays far below the median threshold
    g, _ = _run(scenario.load('deck', {'duration_s': 60.0}), lambda s: s)
    assert g.counters.creep_detected == 0 and not g.moving
