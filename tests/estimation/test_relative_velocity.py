"""filter.relative_velocity (estimation/relative_velocity.py): the slave rigidly on the master's
body (zero), the LDV (ldv) or the LDV while there is one (auto, the default); an LDV that is
absent or falls silent never stalls the engine (decided on stamps)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.estimation.health import OK
from alignment_core.units import ARCMIN

NS = 1_000_000_000


@pytest.fixture(scope='module')
def deck():
    """40 s of the deck scenario (parked the whole time) and its inputs."""
    sc = scenario.load('deck_paper', overrides={'duration_s': 40.0})
    return sc, pipeline.simulate(sc)


def _with(sc, **kw):
    return dataclasses.replace(sc, filter=dataclasses.replace(sc.filter, **kw))


def _feed(sc, inp, ldv):
    """pipeline.align's order with the given LDV samples; returns the engine and, per ship tick,
    (tick stamp, stamp of the newest output so far)."""
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)
    lag, j_ldv, j_m, newest = [], 0, 0, None
    for k in range(len(inp.ships)):
        t = int(inp.ships.t_ns[k])
        if k > 0:
            f.push_imu(inp.imu[k - 1])
        while j_ldv < len(ldv) and ldv[j_ldv].t_ns <= t:
            f.push_ldv(ldv[j_ldv])
            j_ldv += 1
        while j_m < len(inp.master) and inp.master[j_m].t_ns <= t:
            f.push_master(inp.master[j_m])
            j_m += 1
        out = f.process()
        if out:
            newest = out[-1].t_ns
        lag.append((t, newest))
    f.process(final=True)
    return f, lag


def _mu(f):
    return np.array([e.misalignment for e in f.outputs])


def test_the_default_auto_is_the_ldv_mode_when_there_is_an_ldv(deck):
    sc, inp = deck
    assert sc.filter.relative_velocity == 'auto'
    a = pipeline.align(sc, inp)
    b = pipeline.align(_with(sc, relative_velocity='ldv'), inp)
    np.testing.assert_array_equal(_mu(a), _mu(b))
    assert a.relative_velocity == 'ldv' and a.counters.ldv_ignored == 0


def test_zero_is_the_parked_ldv_match_with_its_own_noise(deck):
    """While parked the LDV only says 'valid, not moving' (its velocity is not used), so relative
    velocity zero with rigid_velocity_sigma_mps equal to the parked allowance is the same filter:
    the same numbers, without an LDV."""
    sc, inp = deck
    parked = sc.filter.parked_velocity_sigma_mps
    ldv = pipeline.align(sc, inp)
    zero = pipeline.align(_with(sc, relative_velocity='zero', rigid_velocity_sigma_mps=parked), inp)
    np.testing.assert_array_equal(_mu(ldv), _mu(zero))
    assert zero.counters.ldv_ignored == len(inp.ldv) and zero.counters.ldv == 0
    d = zero.diagnostics()
    assert d.relative_velocity == 'zero' and 'relative velocity zero' in d.message
    assert d.level == OK and 'ldv_silent' not in d.flags
    other = pipeline.align(_with(sc, relative_velocity='zero', rigid_velocity_sigma_mps=10 * parked), inp)
    assert not np.array_equal(_mu(other), _mu(zero))             # its own noise parameter is used


def test_no_ldv_stream_under_auto_is_zero_and_says_so(deck):
    sc, inp = deck
    parked = sc.filter.parked_velocity_sigma_mps
    sc = _with(sc, rigid_velocity_sigma_mps=parked, ldv_silence_s=2.0)
    f, lag = _feed(sc, inp, [])
    zero = pipeline.align(_with(sc, relative_velocity='zero'), inp)
    np.testing.assert_array_equal(_mu(f), _mu(zero))             # nothing lost while it waited
    d = f.diagnostics()
    assert f.relative_velocity == 'zero (no LDV stream)' and 'no LDV stream' in d.message
    assert d.level == OK and 'ldv_silent' not in d.flags
    # it waited 2 s of stamps, then followed the data: outputs at most ~2 s behind the newest tick
    worst = max(t - (n if n is not None else inp.ships.t_ns[0]) for t, n in lag)
    assert worst < 2.2 * NS
    err = (f.outputs[-1].misalignment - inp.sensor_truth['mounting']) / ARCMIN
    assert np.all(np.abs(err) < 3 * f.outputs[-1].misalignment_sigma / ARCMIN)


def test_an_empty_short_bag_still_aligns_at_the_end_under_auto(deck):
    """Fewer stamps than ldv_silence_s and no LDV: the end of the data decides (process(final))."""
    sc, inp = deck
    f = pipeline.align(_with(sc, ldv_silence_s=100.0), dataclasses.replace(inp, ldv=[]))
    assert f.relative_velocity == 'zero (no LDV stream)' and f.counters.updates > 3000


@pytest.mark.parametrize('option', ['auto', 'ldv'])
def test_an_ldv_silent_mid_run_does_not_stall_the_filter(deck, option):
    """The LDV stops at 15 s: the engine stops waiting for it once the IMU and master have run
    ldv_silence_s (2 s) past its last stamp. Under auto the parked matches go on (zero relative
    velocity); under ldv the filter runs free inertial."""
    sc, inp = deck
    sc = _with(sc, relative_velocity=option, ldv_silence_s=2.0)
    cut = int(inp.ships.t_ns[0]) + 15 * NS
    f, lag = _feed(sc, inp, [s for s in inp.ldv if s.t_ns <= cut])
    late = [t - n for t, n in lag if n is not None and t > cut + 3 * NS]
    assert late and max(late) < 0.2 * NS                          # following the data again
    full = pipeline.align(sc, inp)
    d = f.diagnostics()
    assert 'ldv_silent' in d.flags and f.relative_velocity.startswith('ldv silent after t = ')
    if option == 'auto':
        assert f.counters.updates == full.counters.updates and f.latest.matching
    else:
        assert f.counters.updates < 0.5 * full.counters.updates and not f.latest.matching
