"""The compiled checks of what the engine publishes (estimation/publication.py): the output's
covariance parts are numpy's numbers, and the published view's compiled check says an estimate is
good only where its rules do, compiled and interpreted."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from alignment_core.estimation.health import finite
from alignment_core.estimation.outputs import Estimate
from alignment_core.estimation.publication import PublishGuard, covariance_parts, surely_good
from alignment_core.units import DEG

BOUND = 30.0 * DEG
Q0 = np.array([0.1, -0.2, 0.3, 0.0])
Q0[3] = math.sqrt(1.0 - Q0[:3] @ Q0[:3])
FIELDS = ('misalignment', 'misalignment_sigma', 'q_nb', 'attitude_cov', 'x', 'sigma', 'p_w', 'v_b', 'w_b',
          'pose_cov', 'twist_cov', 'state')


def _full(**fields) -> Estimate:
    """An output as the engine makes it: every array present, float64."""
    e = Estimate(t_ns=1, misalignment=np.array([1e-3, -2e-3, 3e-3]), misalignment_sigma=np.full(3, 1e-4),
                 q_nb=Q0.copy(), attitude_cov=np.eye(3) * 1e-8, x=np.full(15, 1e-6), sigma=np.ones(15),
                 bias_gyro=np.zeros(3), bias_accel=np.zeros(3), nis=1.0, updates=1, matching=True,
                 p_w=np.array([1.0, 2.0, 3.0]), v_b=np.array([0.1, 0.0, -0.1]), w_b=np.zeros(3),
                 pose_cov=np.eye(6), twist_cov=np.eye(6) * 2.0, state=np.zeros(15))
    return dataclasses.replace(e, **fields)


def _with(name: str, index: tuple[int, ...], value: float) -> Estimate:
    a = getattr(_full(), name).copy()
    a[index] = value
    return _full(**{name: a})


def _quaternion_cases() -> list[Estimate]:
    """q scaled so that q . q - 1 is near and at the tolerance, either side."""
    out = []
    for d in (0.0, 1e-7, 9.99e-7, 1e-6 - 2e-12, 1e-6 - 1e-13, 1e-6, 1e-6 + 1e-13, 1.001e-6, 1e-3):
        for sign in (1.0, -1.0):
            out.append(_full(q_nb=Q0 * math.sqrt(1.0 + sign * d)))
    return out


def _bound_cases() -> list[Estimate]:
    """The misalignment and its sigma at the bound and an ulp either side."""
    out = []
    for v in (np.nextafter(BOUND, 0.0), BOUND, np.nextafter(BOUND, 1.0)):
        out += [_with('misalignment', (1,), v), _with('misalignment', (2,), -v), _with('misalignment_sigma', (0,), v)]
    return out


def _non_finite_cases() -> list[Estimate]:
    out = []
    for name in FIELDS:
        index = (0,) * getattr(_full(), name).ndim
        out += [_with(name, index, v) for v in (math.nan, math.inf, -math.inf)]
    return out


CASES = [_full()] + _quaternion_cases() + _bound_cases() + _non_finite_cases() + [
    _full(q_nb=Q0[:3] / math.sqrt(Q0[:3] @ Q0[:3])), _full(p_w=None), _full(state=None),
    _full(sigma=np.ones(15, dtype=np.float32)), _full(x=np.full(15, 1e300)), _full(pose_cov=np.eye(6)[:, ::2])]


def _arrays(e: Estimate) -> list:
    return [getattr(e, name) for name in FIELDS]


@pytest.mark.parametrize('k', range(len(CASES)))
def test_the_view_gives_its_rules_answer(k):
    e = CASES[k]
    g = PublishGuard(BOUND)
    assert g.good(e) == g._good_by_rules(e)


@pytest.mark.parametrize('compiled', [True, False], ids=['compiled', 'interpreted'])
def test_the_compiled_check_says_good_only_where_the_rules_do(compiled):
    fun = surely_good if compiled else surely_good.py_func
    g = PublishGuard(BOUND)
    said_good = 0
    for e in CASES:
        arrays = _arrays(e)
        if not all(isinstance(a, np.ndarray) and a.dtype == np.float64 for a in arrays):
            continue
        if fun(*arrays, BOUND):
            assert g._good_by_rules(e)
            said_good += 1
    # the usual output and those clearly inside every rule take the compiled answer
    assert said_good >= 1 + 8 + 4
    assert fun(*_arrays(_full()), BOUND)


def _answer(g: PublishGuard, e: Estimate, rules: bool) -> object:
    try:
        return g._good_by_rules(e) if rules else g.good(e)
    except Exception as err:             # the rules' error is the view's too
        return type(err)


def _with_nan_x(**fields) -> Estimate:
    x = np.full(15, 1e-6)
    x[0] = math.nan
    return _full(x=x, **fields)


ODD = [  # (bound, estimate): what a review found the compiled check answered otherwise
    (BOUND, _full(misalignment_sigma=np.full((3, 1), 1e-4))),            # the rules raise
    (BOUND, _full(misalignment=np.full((3, 1), 1e-3))),
    (BOUND, _with_nan_x(q_nb=Q0.reshape(4, 1))),                         # 2-D q: not compiled
    (BOUND, _with_nan_x(misalignment=np.array(1e-3))),                   # 0-d
    (2**53 + 3, _full(misalignment=np.array([2.0**53 + 4, 0.0, 0.0]))),  # an int bound, exact in Python
    (10**20, _full()), (-10**20, _full()), (np.float16(0.5), _full()), (np.float32(0.5), _full()),
]


@pytest.mark.parametrize('k', range(len(ODD)))
def test_odd_estimates_and_bounds_get_the_rules_answer(k):
    bound, e = ODD[k]
    g = PublishGuard(bound)
    assert _answer(g, e, rules=False) == _answer(g, e, rules=True)


def test_a_quaternion_whose_square_underflows_is_left_to_numpy():
    """Under np.errstate(under='raise') the rules' q . q raises on a 1e-200 component; so does the
    view (the compiled check declines it)."""
    e = _full(q_nb=np.array([1e-200, 0.0, 0.0, 1.0]))
    g = PublishGuard(BOUND)
    assert g.good(e)
    with np.errstate(under='raise'):
        assert _answer(g, e, rules=False) is _answer(g, e, rules=True) is FloatingPointError


def test_the_rules_raise_on_an_empty_misalignment_and_so_does_the_view():
    e = _full(misalignment=np.zeros(0))
    assert not surely_good(*_arrays(e), BOUND)
    with pytest.raises(ValueError):
        PublishGuard(BOUND).good(e)


def _spd(n: int, dtype, seed: int) -> np.ndarray:
    a = np.random.default_rng(seed).standard_normal((n, n))
    return (a @ a.T + n * np.eye(n)).astype(dtype)


@pytest.mark.parametrize('dtype', [np.float64, np.float32])
@pytest.mark.parametrize('first', [0, 2])
@pytest.mark.parametrize('compiled', [True, False], ids=['compiled', 'interpreted'])
def test_the_covariance_parts_are_numpys(dtype, first, compiled):
    """EstimateMaker.keep's numpy lines: the attitude block copied and sqrt(diag P), in P's dtype,
    bit for bit, and finite."""
    fun = covariance_parts if compiled else covariance_parts.py_func
    att = slice(first, first + 3)
    mu, mu_sigma = np.array([1e-3, 2e-3, 3e-3]), np.full(3, 1e-4)
    for seed, n in ((1, 15), (2, 19)):
        p = _spd(n, dtype, seed)
        cov, sigma, ok = fun(p, np.arange(n)[att], mu, mu_sigma)
        want_cov, want_sigma = p[att, att].copy(), np.sqrt(np.diag(p))
        assert cov.dtype == sigma.dtype == dtype and ok
        assert cov.tobytes() == want_cov.tobytes() and sigma.tobytes() == want_sigma.tobytes()


@pytest.mark.parametrize('compiled', [True, False], ids=['compiled', 'interpreted'])
def test_the_covariance_parts_are_finite_where_keep_says_so(compiled):
    """A non-finite attitude cell or diagonal, a negative variance (its sigma NaN), a non-finite
    misalignment or sigma: not finite, as finite() of numpy's parts says; a non-finite cell off
    the attitude block and the diagonal enters neither."""
    fun = covariance_parts if compiled else covariance_parts.py_func
    att = np.arange(3)
    cases = []
    for cell in ((0, 1), (2, 2), (5, 5), (7, 8)):
        for v in (math.nan, math.inf, -math.inf, -1.0):
            p = _spd(15, np.float64, 3)
            p[cell] = v
            cases.append((p, np.zeros(3), np.ones(3)))
    for v in (math.nan, math.inf):
        cases += [(_spd(15, np.float64, 3), np.array([0.0, v, 0.0]), np.ones(3)),
                  (_spd(15, np.float64, 3), np.zeros(3), np.array([v, 1.0, 1.0]))]
    verdicts = set()
    for p, mu, mu_sigma in cases:
        with np.errstate(invalid='ignore'):
            want_cov, want_sigma = p[:3, :3].copy(), np.sqrt(np.diag(p))
        want = finite(want_cov, want_sigma) and finite(mu, mu_sigma)
        with np.errstate(invalid='ignore'):          # interpreted, numpy warns of a negative variance's root
            cov, sigma, ok = fun(p, att, mu, mu_sigma)
        assert ok == want
        np.testing.assert_array_equal(cov, want_cov)
        np.testing.assert_array_equal(sigma, want_sigma)
        verdicts.add(ok)
    assert verdicts == {True, False}
