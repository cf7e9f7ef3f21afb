"""The deck displacement the engine integrates from the LDV once the aircraft moves: a dropout in
the stroke must not drop the distance the aircraft ran while the LDV was blind."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.engine import TransferAlignment
from alignment_core.samples import LdvSample


@pytest.mark.parametrize('blind', [(), tuple(range(20, 45)), tuple(range(20, 45)) + tuple(range(60, 62))])
def test_a_stroke_of_constant_acceleration_is_integrated_across_ldv_dropouts(blind):
    """Moving at 1 m/s, then 30 m/s^2 for 0.8 s (samples every 10 ms), the LDV blind for the
    samples in `blind`: the displacement is v0 T + a T^2 / 2 = 10.4 m (closed form) whatever the
    dropouts, as the trapezoid across a gap is exact for a constant acceleration (the distance
    run in a gap was dropped before: 2.76 m in the first case with a gap)."""
    sc = scenario.load('deck_paper', {'duration_s': 2.0})
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)
    f._launch._moving = True                       # the launch is the detector's business (its own tests)
    v0, a, dt = 1.0, 30.0, 0.01
    for k in range(81):
        v = np.array([v0 + a * k * dt, 0.0, 0.0])
        f._record_ldv(LdvSample(t_ns=k * 10_000_000, v_s=v, sigma=0.01, valid=k not in blind))
    t = 0.8
    assert f.deck_motion.displacement[0] == pytest.approx(v0 * t + 0.5 * a * t * t, rel=1e-12)


def test_a_dropout_longer_than_the_bridge_is_not_bridged():
    """A gap in slow motion over TRAPEZOID_MAX_NS (1 s) is not integrated across (a taxi: the IMU
    would not bridge it either, the deck's motion felt over that long swamping a slow run): the
    displacement is the moving run's before the gap plus the one after it, by the same
    closed form on each side."""
    sc = scenario.load('deck_paper', {'duration_s': 2.0})
    f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)
    f._launch._moving = True
    for k in range(141):                     # valid 0-0.1 s and 1.31-1.4 s at 2 m/s, blind between
        valid = k <= 10 or k >= 131
        f._record_ldv(LdvSample(t_ns=k * 10_000_000, v_s=np.array([2.0, 0.0, 0.0]), sigma=0.01, valid=valid))
    assert f.deck_motion.displacement[0] == pytest.approx(2.0 * (0.1 + 0.09), rel=1e-12)
