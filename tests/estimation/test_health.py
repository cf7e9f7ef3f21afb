"""Numerical breakdown is caught by the engine: counted, the last good estimate held (healthy
False) while the slave runs free inertial, never an exception out of a node's callback."""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation import health
from alignment_core.estimation.health import ERROR

SHORT = {'duration_s': 6.0, 'aircraft.catapult.launch_time_s': 3.0}
# a 0.01' attitude match against a 1 deg prior: a variance ratio of 3.6e7, beyond float32's 24-bit
# significand (1.7e7); the update's P - K H P cancels below single precision's resolution of P
F32_SEED003 = {**SHORT, 'filter.model': 'seed003_21', 'filter.float32': True,
               'filter.attitude_match_sigma_arcmin': 0.01}


@pytest.mark.parametrize('algorithm', ['kf', 'fading_tested', 'stf_multiple'])
def test_single_precision_seed003_breakdown_is_held_not_raised(algorithm):
    """seed 003's finding: the non-square-root filters lose positive definiteness in float32 on
    the 21-state model (here within the first second: F32_SEED003's variance ratio). It used to
    raise LinAlgError (fading_tested, stf_multiple) or run on with negative variances (kf)."""
    sc = scenario.load('catapult_paper', {**F32_SEED003, 'filter.algorithm': algorithm}, seed=3)
    res = pipeline.run(sc, keep_truth=False)
    f, out = res.filter, res.estimates
    assert f.counters.numerical_failures >= 1 and not f.healthy and f.failure
    assert len(out) == 61 and not out[-1].healthy                # one output per 100 ms to the end
    held = [e for e in out if not e.healthy]
    for e in held:
        assert np.array_equal(e.misalignment, held[0].misalignment)
        assert np.array_equal(e.sigma, held[0].sigma)
        assert np.all(np.isfinite(e.sigma)) and np.all(np.isfinite(e.misalignment))
    assert not np.array_equal(held[0].q_nb, held[-1].q_nb)      # the slave runs on, free inertial
    assert held[-1].updates == held[0].updates


@pytest.mark.parametrize('algorithm', ['carlson', 'ud', 'combined'])
def test_square_root_filters_stay_healthy_in_single_precision(algorithm):
    sc = scenario.load('catapult_paper', {**F32_SEED003, 'filter.algorithm': algorithm}, seed=3)
    res = pipeline.run(sc, keep_truth=False)
    assert res.filter.counters.numerical_failures == 0 and all(e.healthy for e in res.estimates)


@pytest.mark.parametrize('algorithm', ['kf', 'carlson'])
def test_a_corrupted_master_sample_breaks_the_filter_down_and_the_last_estimate_is_held(algorithm):
    """Float64, with the master speed range opened up (filter.master_speed_max_mps; by default a
    1e200 m/s sample is rejected at the push, see the next test): the innovation squared of a
    master velocity corrupted to ~1e200 m/s overflows (a non-finite NIS) at its update. The
    outputs before it are the clean run's, the ones after hold the last good estimate (the output
    at the master sample before it), and the engine keeps publishing to the end."""
    sc = scenario.load('catapult_paper', {**SHORT, 'filter.algorithm': algorithm, 'filter.master_speed_max_mps': 1e300})
    inp = pipeline.simulate(sc)
    ref = pipeline.align(sc, inp)
    k = 201                                   # the master sample after the output at 2.0 s
    master = list(inp.master)
    master[k] = dataclasses.replace(master[k], v_b=master[k].v_b * 1e200)
    with warnings.catch_warnings():           # numpy's overflow warning (compiled kernels give none)
        warnings.filterwarnings('ignore', message='overflow', category=RuntimeWarning)
        f = pipeline.align(sc, dataclasses.replace(inp, master=master))
    assert f.counters.numerical_failures == 1 and not f.healthy and 'not finite' in f.failure
    assert f.counters.updates == k - 1        # the first sample initialises
    out = f.outputs
    good = [e for e in out if e.healthy]
    assert len(good) == 21 and len(out) == len(ref.outputs)
    for a, b in zip(good, ref.outputs):
        assert np.array_equal(a.misalignment, b.misalignment) and np.array_equal(a.sigma, b.sigma)
    for e in out[21:]:
        assert np.array_equal(e.misalignment, good[-1].misalignment) and np.array_equal(e.sigma, good[-1].sigma)
        assert not e.matching and e.level == ERROR and 'breakdown' in e.flags
    # what a node publishes: the same (the engine holds the estimate itself), flagged, never NaN
    for e, o in zip(f.published[21:], out[21:]):
        assert np.array_equal(e.misalignment, o.misalignment) and 'held' in e.flags
        assert np.all(np.isfinite(e.q_nb)) and np.all(np.isfinite(e.p_w)) and np.all(np.isfinite(e.pose_cov))


def test_by_default_an_absurd_master_velocity_is_rejected_at_the_push():
    """The same 1e200 m/s master sample is beyond filter.master_speed_max_mps (100 m/s): rejected
    and counted as 'range', it never reaches the filter, which stays healthy and misses one update."""
    sc = scenario.load('catapult_paper', SHORT)
    inp = pipeline.simulate(sc)
    ref = pipeline.align(sc, inp)
    master = list(inp.master)
    master[201] = dataclasses.replace(master[201], v_b=master[201].v_b * 1e200)
    f = pipeline.align(sc, dataclasses.replace(inp, master=master))
    assert f.counters.rejected_range == 1 and f.counters.numerical_failures == 0 and f.healthy
    assert f.counters.updates == ref.counters.updates - 1
    assert all(e.level < ERROR for e in f.outputs)


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
def test_the_health_check_refuses_each_kind_of_breakdown_and_only_those(dtype):
    """A non-finite state, a zero, negative or non-finite variance are a breakdown; off-diagonal
    cells are not checked; values whose sum would overflow are each finite, so healthy (a sum
    of the elements would have called them non-finite). Compiled and interpreted agree."""
    big = np.finfo(dtype).max
    x, p = np.zeros(4, dtype), np.eye(4, dtype=dtype)
    cases = [((x, p), True)]
    for bad in (np.nan, np.inf, -np.inf):
        xb = x.copy()
        xb[2] = bad
        cases.append(((xb, p), False))
    for bad in (0.0, -1e-30, np.nan, np.inf):
        pb = p.copy()
        pb[3, 3] = bad
        cases.append(((x, pb), False))
    po = p.copy()
    po[0, 1] = np.nan                             # off the diagonal: not the check's concern
    cases.append(((x, po), True))
    cases.append(((np.full(4, big, dtype), np.eye(4, dtype=dtype) * big), True))
    for (xi, pi), want in cases:
        assert health.healthy(xi, pi) is want
        assert health.healthy.py_func(xi, pi) is want
        if want:
            health.check_health(xi, pi)
        else:
            with pytest.raises(health.NumericalBreakdownError):
                health.check_health(xi, pi)


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
def test_finite_refuses_any_non_finite_element_of_any_array(dtype):
    """A NaN or an inf in any element of any argument (vectors, matrices, non-contiguous views,
    lists) is not finite; large finite vectors and matrices whose sum would overflow are. The compiled check
    of one array agrees with its interpreted form and with numpy's isfinite."""
    big = np.finfo(dtype).max
    ok = (np.ones(3, dtype), np.ones((6, 6), dtype), np.ones(21, dtype), np.full((3, 3), big, dtype))
    assert health.finite(*ok) and health.finite() and health.finite([1.0, 2.0])
    for k in range(len(ok)):
        for bad in (np.nan, np.inf, -np.inf):
            arrays = [a.copy() for a in ok]
            arrays[k].flat[-1] = bad
            assert not health.finite(*arrays)
            assert not health.all_finite(arrays[k]) and not health.all_finite.py_func(arrays[k])
    m = np.ones((6, 6), dtype)
    m[1, 1] = np.nan
    assert not health.finite(np.diagonal(m)) and not health.finite(m[1::2, 1::2]) and not health.finite(m.T)
    assert health.finite(m[::2, ::2])                 # a view that misses the NaN
    assert not health.finite([1.0, np.inf])
    huge = np.array([big, big, 0.0], dtype)            # finite, though its sum overflows
    assert health.finite(huge) and health.finite(np.ones(3, dtype), huge, -huge)
    assert not health.finite(huge, np.array([0.0, np.nan, 0.0], dtype))
    assert health.finite(huge, np.array([1 + 1j])) and not health.finite(huge, np.array([complex(np.inf, 0.0)]))
    rng = np.random.default_rng(1)
    for _ in range(50):
        a = rng.standard_normal((4, 5)).astype(dtype)
        a[rng.random((4, 5)) < 0.05] = rng.choice([np.nan, np.inf, -np.inf])
        assert health.all_finite(a) == bool(np.all(np.isfinite(a))) == health.all_finite.py_func(a)
