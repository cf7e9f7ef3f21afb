"""The health report follows the stamps processed, not arrival timing (estimation/input_streams.py):
an LDV that arrives late (in the graph the LDV node runs behind the IMU's) but complete gives the
same outputs and the same report (level, flags, message) at every output as in-order feeding, and
no 'ldv_silent'; a gap in the LDV's own stamps, an LDV that stops, a master that stops are still
reported (WARN), and a rejected sample counts the same however late it arrived."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.estimation.health import OK, WARN

NS = 1_000_000_000
SC = scenario.load('catapult_paper', {'duration_s': 15.0, 'aircraft.catapult.launch_time_s': 8.0}, seed=3)


@pytest.fixture(scope='module')
def inp():
    return pipeline.simulate(SC)


def _feed(sc, inp, ldv_delay_ns=0, ldv=None, master=None):
    """pipeline.align's order, the LDV sample stamped s pushed at the first ship tick at or after
    s + ldv_delay_ns (the LDV node running behind; a function of s if callable); process() at
    every tick. Returns the engine and, per tick, what it waits for."""
    delay = ldv_delay_ns if callable(ldv_delay_ns) else (lambda s: ldv_delay_ns)
    ldv = inp.ldv if ldv is None else ldv
    master = inp.master if master is None else master
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)
    waiting, j_ldv, j_m = [], 0, 0
    for k in range(len(inp.ships)):
        t = int(inp.ships.t_ns[k])
        if k > 0:
            f.push_imu(inp.imu[k - 1])
        while j_ldv < len(ldv) and ldv[j_ldv].t_ns + delay(ldv[j_ldv].t_ns) <= t:
            f.push_ldv(ldv[j_ldv])
            j_ldv += 1
        while j_m < len(master) and master[j_m].t_ns <= t:
            f.push_master(master[j_m])
            j_m += 1
        f.process()
        waiting.append((t, f.waiting_for()))
    while j_ldv < len(ldv):                       # what was still in flight at the end
        f.push_ldv(ldv[j_ldv])
        j_ldv += 1
    f.process(final=True)
    return f, waiting


def _reports(f):
    return [(e.t_ns, e.report) for e in f.outputs]


def _same_run(a, b):
    np.testing.assert_array_equal([e.misalignment for e in a.outputs], [e.misalignment for e in b.outputs])
    assert _reports(a) == _reports(b)
    assert a.status() == b.status() and a.diagnostics().message == b.diagnostics().message


def test_a_late_but_complete_ldv_is_not_silent(inp):
    """1.5 s of stamps behind the IMU on arrival, more than silence_warn_s (1 s): the stamp order
    waits for it, so the outputs, the report at each of them and the final status are those of
    in-order feeding, all OK; it keeps delivering, so it is never waited for as silent either."""
    delay = int(1.5 * NS)
    assert delay > SC.filter.silence_warn_s * NS
    ref, _ = _feed(SC, inp)
    late, waiting = _feed(SC, inp, ldv_delay_ns=delay)
    _same_run(late, ref)
    assert len(late.outputs) > 100 and late.deck_motion.t_launch_ns is not None
    assert all(e.report.level == OK and e.report.flags == () for e in late.outputs)
    assert all(w == () for t, w in waiting if t > inp.ships.t_ns[0] + 2 * NS)
    assert late.status() == (OK, ())


def test_an_ldv_later_than_ldv_silence_s_on_arrival_is_not_declared_silent(inp):
    """ldv_silence_s 2 s, the LDV 0.5 s late at first and 0.3 s more per second of stamps (4.6 s
    late at the end): it keeps delivering, so the engine keeps waiting for it
    (relative_velocity.py): the run is the in-order one, relative velocity from the LDV."""
    sc = dataclasses.replace(SC, filter=dataclasses.replace(SC.filter, ldv_silence_s=2.0))
    t0 = int(inp.ships.t_ns[0])
    ref, _ = _feed(sc, inp)
    late, _ = _feed(sc, inp, ldv_delay_ns=lambda s: NS // 2 + int(0.3 * (s - t0)))
    _same_run(late, ref)
    assert late.relative_velocity == 'ldv' and late.counters.ldv_ignored == 0
    assert late.counters.ldv == len(inp.ldv)


def test_a_gap_in_the_ldv_stamps_is_reported_at_the_outputs_inside_it_however_it_arrives(inp):
    """No LDV sample from 4 s to 7 s (parked; shorter than ldv_silence_s, so the engine waits):
    the outputs whose stamp is more than silence_warn_s past the last LDV stamp before them are
    flagged 'ldv_silent' (WARN), the others not, the same in order and 1.5 s late."""
    t0 = int(inp.ships.t_ns[0])
    ldv = [s for s in inp.ldv if not t0 + 4 * NS < s.t_ns < t0 + 7 * NS]
    ref, _ = _feed(SC, inp, ldv=ldv)
    late, _ = _feed(SC, inp, ldv_delay_ns=int(1.5 * NS), ldv=ldv)
    _same_run(late, ref)
    stamps = np.array([s.t_ns for s in ldv])
    silence_ns = SC.filter.silence_warn_s * NS
    flagged = 0
    for e in late.outputs:
        last = stamps[stamps <= e.t_ns].max()
        silent = e.t_ns - last > silence_ns
        flagged += silent
        assert ('ldv_silent' in e.report.flags) == silent, e.t_ns
        assert (e.report.level == WARN and 'ldv silent' in e.report.message) == silent, e.t_ns
    assert flagged >= 15                     # outputs at 10 Hz from 5 s to 7 s


def test_an_ldv_that_stops_is_reported_from_its_last_stamp_on(inp):
    """The LDV stops at 6 s (parked): once ldv_silence_s (2 s) of IMU and master stamps passed,
    the engine stops waiting; the outputs from 1 s after its last stamp on say 'ldv_silent'."""
    sc = dataclasses.replace(SC, filter=dataclasses.replace(SC.filter, ldv_silence_s=2.0))
    cut = int(inp.ships.t_ns[0]) + 6 * NS
    ldv = [s for s in inp.ldv if s.t_ns <= cut]
    f, waiting = _feed(sc, inp, ldv=ldv)
    last = ldv[-1].t_ns
    after = [e for e in f.outputs if e.t_ns > last + sc.filter.silence_warn_s * NS]
    assert len(after) > 50 and all('ldv_silent' in e.report.flags and e.report.level >= WARN for e in after)
    assert all('ldv_silent' not in e.report.flags for e in f.outputs if e.t_ns <= last)
    # while the engine waited for it (between 1 s and 2 s of stamps past it) the node can say so
    assert any(w == ('ldv',) for t, w in waiting if last + 1.2 * NS < t < last + 1.9 * NS)
    assert 'ldv_silent' in f.status()[1]


def test_a_master_that_stops_is_waited_for_and_reported_at_the_end(inp):
    """The master stops at 6 s: there is no output after it (they come with master samples); the
    engine says it waits for the master from 1 s of stamps past its last sample on, and the end
    of the data (all processed) reports it silent."""
    cut = int(inp.ships.t_ns[0]) + 6 * NS
    master = [s for s in inp.master if s.t_ns <= cut]
    f, waiting = _feed(SC, inp, master=master)
    last = master[-1].t_ns
    assert all(e.t_ns <= last for e in f.outputs)
    assert all(w == ('master',) for t, w in waiting if t > last + 1.05 * NS)
    assert all(w == () for t, w in waiting if inp.ships.t_ns[0] + 1.05 * NS < t <= last + 0.95 * NS)
    level, flags = f.status()
    assert level == WARN and 'master_silent' in flags and 'master silent' in f.diagnostics().message


def test_a_rejected_sample_counts_in_the_report_the_same_however_late_it_arrived(inp):
    """A non-finite LDV sample at 5 s: WARN from the first output after it on (its stream's next
    sample), in order and 1.5 s late alike; OK before."""
    t0 = int(inp.ships.t_ns[0])
    k = next(i for i, s in enumerate(inp.ldv) if s.t_ns > t0 + 5 * NS)
    bad = dataclasses.replace(inp.ldv[k], v_s=np.array([np.nan, 0.0, 0.0]))
    ldv = [*inp.ldv[:k], bad, *inp.ldv[k + 1:]]
    ref, _ = _feed(SC, inp, ldv=ldv)
    late, _ = _feed(SC, inp, ldv_delay_ns=int(1.5 * NS), ldv=ldv)
    _same_run(late, ref)
    assert late.counters.rejected_nonfinite == 1
    for e in late.outputs:
        assert e.report.level == (WARN if e.t_ns >= inp.ldv[k + 1].t_ns else OK), e.t_ns
