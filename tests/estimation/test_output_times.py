"""The times an output refers to: the slave solution's (its newest IMU sample, `navigation_ns`),
and the misalignment's (its last master update's, `validity_ns`), against the master stamp it is
published at (`t_ns`). A master with transport jitter stamps off the IMU's grid; a beam that loses
its reflector before the release leaves the misalignment held where it was last matched."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario

SHORT = {'duration_s': 11.0, 'aircraft.catapult.launch_time_s': 5.0}


@pytest.fixture(scope='module')
def carrier():
    sc = scenario.load('catapult', SHORT, seed=2)
    inp = pipeline.simulate(sc)
    return sc, inp, pipeline.align(sc, inp).outputs


def test_the_slave_solution_is_stamped_with_its_imu_sample(carrier):
    """The jittered 50 Hz master stamps fall between IMU samples; the attitude published with one
    is the INS's at the newest IMU sample processed, never later than the stamp."""
    sc, inp, est = carrier
    t = np.array([e.t_ns for e in est])
    nav = np.array([e.navigation_ns for e in est])
    assert np.all(np.isin(nav, [s.t_ns for s in inp.imu]))
    assert np.all((t - nav >= 0) & (t - nav < sc.dt_ns))
    assert np.count_nonzero(t != nav) > len(t) // 2          # off the grid: the times differ


def test_a_held_misalignment_stays_valid_where_it_was_matched(carrier):
    """After the last update (the beam loses the reflector during the stroke, then the flight) the
    misalignment repeats bit for bit and keeps its last match's time; while matching it is valid
    at the stamp (no latency told)."""
    sc, inp, est = carrier
    updates = np.array([e.updates for e in est])
    last = int(np.flatnonzero(np.diff(updates) > 0)[-1]) + 1       # the output of the last update
    held = est[last + 1:]
    assert len(held) > 20
    assert all(np.array_equal(e.misalignment, est[last].misalignment) for e in held)
    assert {e.validity_ns for e in held} == {est[last].validity_ns}
    assert est[last].validity_ns <= est[last].t_ns < held[0].t_ns
    release = int(inp.ships.t_ns[inp.truth['on_deck']][-1])
    assert est[last].t_ns < release


def test_on_the_papers_deck_every_time_is_the_stamp():
    """Master and IMU on one 100 Hz grid, no latency: all three times coincide (the estimates and
    scores of every paper scenario are unchanged by them)."""
    sc = scenario.load('deck_paper', {'duration_s': 6.0})
    est = pipeline.run(sc, keep_truth=False).estimates
    assert all(e.navigation_ns == e.t_ns for e in est)
    assert all(e.validity_ns == e.t_ns for e in est[1:])
