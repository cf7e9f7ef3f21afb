"""The compiled accepts of estimation/plausibility.py decide nothing of their own: on samples at,
near and beyond every limit, non-finite, huge, tiny, of other types and lengths, the checks
give the rules' answers (the same object, or the same normalised bits), and the accepts say yes
only where the rules accept as given. Compiled and interpreted alike."""
from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from alignment_core.compiled import is_float64_vector as vector
from alignment_core.estimation import plausibility as pl
from alignment_core.estimation.config import FilterConfig
from alignment_core.samples import ImuSample, LdvSample, MasterSample
from alignment_core.units import G0

LIM = pl.Limits.of(FilterConfig())
UP = math.nextafter


def _edges(limit: float) -> list[float]:
    """Values at, just inside and just beyond a limit, far inside and beyond, and non-finite."""
    return [0.0, -0.0, 1e-300, 0.5 * limit, UP(limit, 0.0), limit, UP(limit, math.inf), -limit, 2.0 * limit,
            1e308, math.inf, -math.inf, math.nan]


def _imu_samples() -> list[ImuSample]:
    out = []
    for g, a in itertools.product(_edges(LIM.gyro_max), _edges(LIM.accel_max)):
        out.append(ImuSample(1, np.array([0.01, g, -0.02]), np.array([a, 0.1, -9.8])))
    out += [ImuSample(1, np.array([0.01, 0.0, 0.0], dtype=np.float32), np.array([0.0, 0.0, -9.8])),
            ImuSample(1, np.array([0.01, 0.0, 0.0, 0.0])[::1][:3], np.array([0.0, 0.0, -9.8])),
            ImuSample(1, np.arange(6.0)[::2], np.array([0.0, 0.0, -9.8]))]      # a strided view
    return out


def _norm_edges(limit: float) -> list[np.ndarray]:
    """3-vectors whose norm is at, within an ulp or a margin of, and beyond a limit."""
    u = np.array([0.6, 0.0, 0.8])
    out = [u * limit * f for f in (0.0, 0.5, 1.0 - 2e-9, 1.0 - 1e-9, 1.0 - 1e-12, 1.0, 1.0 + 1e-15, 1.0 + 1e-9, 2.0)]
    out += [np.array([limit, 0.0, 0.0]), np.array([UP(limit, 0.0), 0.0, 0.0]), np.array([1e200, 1e200, 0.0]),
            np.array([1e-200, 0.0, 0.0]), np.array([math.nan, 0.0, 0.0]), np.array([0.0, math.inf, 0.0])]
    return out


def _quaternions() -> list[np.ndarray]:
    q = np.array([0.1, -0.2, 0.3, 0.0])
    q[3] = math.sqrt(1.0 - q[:3] @ q[:3])
    out = [q * s for s in (1.0, 1.0 + 2e-16, 1.0 + 5e-13, 1.0 + 9.99e-13, 1.0 + 1e-12, 1.0 + 1.01e-12, 1.0 - 1e-12,
                           1.0 + 5e-4, 1.0 + LIM.quaternion_tol, 1.0 + 2e-3, 2.0, 0.0)]
    return out + [np.array([0.0, 0.0, 0.0, 1.0]), np.array([math.nan, 0.0, 0.0, 1.0]), np.array([0.0, 0.0, 1.0])]


def _master_samples() -> list[MasterSample]:
    p, q, v, w = np.array([100.0, 50.0, 0.0]), _quaternions()[0], np.array([5.0, 0.0, 0.0]), np.array([0.01, 0, 0])
    out = [MasterSample(1, p, qq, v, w) for qq in _quaternions()]
    out += [MasterSample(1, p, q, vv, w) for vv in _norm_edges(LIM.master_speed)]
    out += [MasterSample(1, p, q, v, ww) for ww in _norm_edges(LIM.master_rate)]
    out += [MasterSample(1, pp, q, v, w) for pp in _norm_edges(LIM.position)]
    out.append(MasterSample(1, p, q.astype(np.float32), v, w))
    return out


def _beams() -> list[np.ndarray]:
    """Lines of sight whose norm is within, at and beyond the beam's unit tolerance."""
    u = np.array([0.6, -0.48, 0.64])
    out = [u * s for s in (1.0, 1.0 + 5e-7, 1.0 + 1e-6, 1.0 + 1.0000001e-6, 1.0 - 1e-6, 1.0 + 2e-6, 0.0)]
    return out + [np.array([math.nan, 0.0, 1.0]), np.array([0.6, 0.0, 0.8], dtype=np.float32)]


def _ldv_samples() -> list[LdvSample]:
    out = [LdvSample(1, vv, 0.01, True) for vv in _norm_edges(LIM.ldv_speed)]
    out += [LdvSample(1, vv, 0.01, True, beam=np.array([0.6, 0.0, 0.8])) for vv in _norm_edges(LIM.ldv_speed)]
    out += [LdvSample(1, np.array([0.1, 0.0, 0.0]), 0.01, True, beam=b) for b in _beams()]
    out += [LdvSample(1, np.array([0.1, 0.0, 0.0]), 0.01, True, beam=np.array([1.0, 0.0, 0.0])),
            LdvSample(1, np.full(3, math.nan), math.nan, False), LdvSample(1, np.array([1, 2, 3]), 0.01, True)]
    return out


def test_imu_checks_give_the_rules_answers():
    for s in _imu_samples():
        assert pl.imu_reason(s, LIM) == pl.imu_rules(s, LIM), s


def test_master_checks_give_the_rules_answers_to_the_bit():
    for s in _master_samples():
        got, why = pl.master_check(s, LIM)
        want, want_why = pl.master_rules(s, LIM)
        assert why == want_why, s
        if want is s:
            assert got is s
        elif want is None:
            assert got is None
        else:
            assert got is not None and got.q_nb.tobytes() == want.q_nb.tobytes()


def test_ldv_checks_give_the_rules_answers():
    for lim in (LIM, pl.Limits.of(FilterConfig(ldv_mode='beam'))):
        for s in _ldv_samples():
            assert pl.ldv_reason(s, lim) == pl.ldv_rules(s, lim), s


@pytest.mark.parametrize('compiled', [True, False])
def test_the_accepts_say_yes_only_where_the_rules_pass_the_sample_as_given(compiled):
    imu = pl.imu_plausible if compiled else pl.imu_plausible.py_func
    master = pl.master_plausible if compiled else pl.master_plausible.py_func
    norm = pl.norm_within if compiled else pl.norm_within.py_func
    beam = pl.beam_plausible if compiled else pl.beam_plausible.py_func
    with np.errstate(over='ignore'):          # interpreted, numpy's scalars warn where a square overflows
        yes = _accepted(imu, master, norm, beam)
    assert yes > 20                       # the usual samples are accepted without the rules


def _accepted(imu, master, norm, beam) -> int:
    yes = 0
    for s in _imu_samples():
        if vector(s.gyro) and vector(s.accel) and imu(s.gyro, s.accel, LIM.gyro_max, LIM.accel_max):
            yes += 1
            assert pl.imu_rules(s, LIM) == ''
    for m in _master_samples():
        arrays = (m.p_w, m.q_nb, m.v_b, m.w_b)
        if all(vector(a) for a in arrays) and master(*arrays, LIM.quaternion_tol, LIM.master_speed,
                                                          LIM.master_rate, LIM.position):
            yes += 1
            assert pl.master_rules(m, LIM) == (m, '')
    for v in _norm_edges(LIM.ldv_speed):
        if norm(v, 3, LIM.ldv_speed):
            yes += 1
            assert math.hypot(*v.tolist()) <= LIM.ldv_speed
    beam_lim = pl.Limits.of(FilterConfig(ldv_mode='beam'))
    for s in _ldv_samples():
        if s.beam is not None and vector(s.v_s) and vector(s.beam) and beam(s.v_s, s.beam, LIM.ldv_speed):
            yes += 1
            assert pl.ldv_rules(s, beam_lim) == ''
    return yes


def test_the_accepts_leave_a_limit_to_the_rules():
    """At a norm's limit, or a quaternion's norm one ulp-scale step from rounding, the accept
    says no (the margin); the rules then accept or reject."""
    assert not pl.norm_within(np.array([LIM.ldv_speed, 0.0, 0.0]), 3, LIM.ldv_speed)
    assert pl.norm_within(np.array([LIM.ldv_speed * (1.0 - 2e-9), 0.0, 0.0]), 3, LIM.ldv_speed)
    assert pl.within(np.array([LIM.gyro_max, 0.0, 0.0]), LIM.gyro_max)          # the full scale itself: in range
    assert not pl.within(np.array([UP(LIM.gyro_max, math.inf), 0.0, 0.0]), LIM.gyro_max)
    assert not pl.within(np.array([16.0 * G0, 0.0]), LIM.accel_max)      # not a 3-vector
    assert not pl.beam_plausible(np.zeros(3), np.array([0.0, 1.0]), LIM.ldv_speed)
    assert pl.beam_plausible(np.zeros(3), np.array([0.0, 1.0 + 0.99e-6, 0.0]), LIM.ldv_speed)
    assert not pl.beam_plausible(np.zeros(3), np.array([0.0, 1.0 + 1e-6, 0.0]), LIM.ldv_speed)


@pytest.mark.parametrize('limit', [1e200, 1.3408e154, 1e150, 1e-150, 4.4668e-158, 1e-200, 5e-324, 0.0, -0.0, -5.0,
                                   -math.inf, math.inf, math.nan])
def test_any_limit_leaves_what_the_accept_cannot_decide_to_the_rules(limit):
    """Limits whose squares would overflow or fall below the normal range (a configured 1e200 m/s
    accepted a 1e300 m/s velocity before), zero, negative and non-finite ones: the checks give
    the rules' answers for vectors at, around and far from the limit."""
    lim = dataclasses.replace(LIM, master_speed=limit, master_rate=limit, position=limit, ldv_speed=limit)
    values = [1e300, 1e200, 1e155, 1e-170, 5e-324, 1.0, 0.0]
    if math.isfinite(limit) and limit != 0.0:
        values += [abs(limit) * f for f in (0.5, 1.0 - 1e-12, 1.0, 1.0 + 1e-12, 1.00001, 2.0)]
    u, q = np.array([1.0, 0.0, 0.0]), _quaternions()[0]
    for x in values:
        v = u * x
        for s in (LdvSample(1, v, 0.01, True), LdvSample(1, v, 0.01, True, beam=np.array([0.6, 0.0, 0.8]))):
            for lm in (lim, dataclasses.replace(lim, ldv_beam=True)):
                assert pl.ldv_reason(s, lm) == pl.ldv_rules(s, lm), (x, s)
        for m in (MasterSample(1, v, q, np.zeros(3), np.zeros(3)), MasterSample(1, np.zeros(3), q, v, np.zeros(3)),
                  MasterSample(1, np.zeros(3), q, np.zeros(3), v)):
            got, want = pl.master_check(m, lim), pl.master_rules(m, lim)
            assert got[1] == want[1] and (got[0] is m) == (want[0] is m), (x, m)


def test_configured_limits_are_floats_for_the_accepts():
    """An int or numpy scalar in the config (10**20 m passes validation) reaches the kernels as a
    float: no overflow or typing error where the rules answer."""
    lim = pl.Limits.of(FilterConfig(position_max_m=10**20, ldv_speed_max_mps=np.float32(150.0)))
    assert type(lim.position) is float and type(lim.ldv_speed) is float
    m = _master_samples()[0]
    assert pl.master_check(m, lim) == pl.master_rules(m, lim)
    s = LdvSample(1, np.array([1.0, 0.0, 0.0]), 0.01, True)
    assert pl.ldv_reason(s, lim) == pl.ldv_rules(s, lim) == ''


def test_the_interpreted_accepts_square_nothing_that_overflows():
    """Interpreted (NUMBA_DISABLE_JIT), numpy's scalars would warn or raise where a square
    overflows: a component beyond the limit, or beyond 2 for a unit vector, decides first."""
    big = np.array([1e200, 0.0, 0.0])
    with np.errstate(over='raise'):
        assert not pl.norm_within.py_func(big, 3, 150.0)
        assert not pl.near_unit.py_func(np.array([1e200, 0.0, 0.0, 1.0]), 4, 1e-12)
        assert not pl.beam_plausible.py_func(np.zeros(3), big, 150.0)
