"""The compiled strapdown step equals its interpreted form bit for bit, and Strapdown.update
keeps its contract (new arrays, the increments kept for the next coning and sculling terms)."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.navigation.strapdown import NavState, Strapdown, step


def _case(rng):
    q = rng.standard_normal(4)
    q /= np.sqrt(q @ q)
    return (rng.standard_normal(3) * 1e-3, rng.standard_normal(3) * 0.1, rng.standard_normal(3) * 1e-3,
            rng.standard_normal(3) * 0.1, q, rng.standard_normal(3) * 50.0,
            float(rng.uniform(-1.4, 1.4)), float(rng.uniform(-3.0, 3.0)), float(rng.uniform(0.0, 9000.0)),
            float(rng.choice([0.0025, 0.005, 0.01, 0.02])))


def test_step_compiled_equals_interpreted():
    rng = np.random.default_rng(11)
    for _ in range(300):
        args = _case(rng)
        got, want = step(*args), step.py_func(*args)
        for a, b in zip(got, want):
            if isinstance(a, np.ndarray):
                assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
            else:                                   # interpreted on arrays: numpy float64 scalars
                assert type(a) is float and a == float(b)


def test_a_zero_interval_raises_as_the_float_code_did():
    """The step's float arithmetic keeps Python's error model (Strapdown.update's Python floats
    raised ZeroDivisionError before it was compiled), not numpy's inf."""
    args = list(_case(np.random.default_rng(12)))
    args[-1] = 0.0
    with pytest.raises(ZeroDivisionError):
        step(*args)


def test_update_replaces_the_state_arrays_and_keeps_the_increments():
    rng = np.random.default_rng(13)
    q0, v0 = np.array([0.0, 0.0, 0.0, 1.0]), np.array([1.0, 2.0, 0.0])
    s = NavState(q_nb=q0, v_n=v0, lat=0.6, lon=0.1, h=10.0)
    sd = Strapdown(s)
    dth, dv = rng.standard_normal(3) * 1e-3, rng.standard_normal(3) * 0.1
    f = sd.update(dth, dv, 0.01)
    assert s.q_nb is not q0 and s.v_n is not v0 and np.array_equal(q0, [0.0, 0.0, 0.0, 1.0])
    assert s.prev_dtheta is dth and s.prev_dv is dv
    assert f.shape == (3,) and sd.c_start.shape == (3, 3) and sd.w_ie.shape == sd.w_en.shape == (3,)
    assert isinstance(s.lat, float) and isinstance(s.lon, float) and isinstance(s.h, float)
    # float32 increments: the same numbers as their float64 values
    s32 = NavState(q_nb=q0, v_n=v0, lat=0.6, lon=0.1, h=10.0)
    d32, v32 = dth.astype(np.float32), dv.astype(np.float32)
    f32 = Strapdown(s32).update(d32, v32, 0.01)
    s64 = NavState(q_nb=q0, v_n=v0, lat=0.6, lon=0.1, h=10.0)
    f64 = Strapdown(s64).update(d32.astype(np.float64), v32.astype(np.float64), 0.01)
    assert np.array_equal(f32, f64) and np.array_equal(s32.q_nb, s64.q_nb) and s32.lat == s64.lat
