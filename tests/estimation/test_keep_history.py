"""A node's engine keeps no history (memory flat over a run): without it, process() returns the
same estimates, outputs / published hold only the latest and the whiteness test no window."""
from __future__ import annotations

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.engine import TransferAlignment


def _feed(sc, inp, keep):
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz, keep_history=keep)
    got = []
    j_ldv = j_master = 0
    for k in range(len(inp.ships)):
        t = int(inp.ships.t_ns[k])
        if k > 0:
            f.push_imu(inp.imu[k - 1])
        while j_ldv < len(inp.ldv) and inp.ldv[j_ldv].t_ns <= t:
            f.push_ldv(inp.ldv[j_ldv])
            j_ldv += 1
        while j_master < len(inp.master) and inp.master[j_master].t_ns <= t:
            f.push_master(inp.master[j_master])
            j_master += 1
        got += f.process()
        assert keep or (len(f.outputs) <= 1 and len(f.published) <= 1)
    got += f.process(final=True)
    return f, got


def test_no_history_same_estimates():
    sc = scenario.load('catapult_paper', {'duration_s': 6.0, 'aircraft.catapult.enabled': False})
    inp = pipeline.simulate(sc)
    full, a = _feed(sc, inp, True)
    lean, b = _feed(sc, inp, False)
    assert len(a) == len(b) == len(full.outputs) > 10
    for x, y in zip(a, b):
        assert x.t_ns == y.t_ns
        np.testing.assert_array_equal(x.misalignment, y.misalignment)
    assert lean.latest.t_ns == full.latest.t_ns
    assert len(full.whiteness.history) == full.whiteness.completed >= 1
    assert lean.whiteness.history == [] and lean.whiteness.last == full.whiteness.last
