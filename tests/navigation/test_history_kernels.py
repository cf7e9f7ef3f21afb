"""The histories' compiled interpolations (navigation/history_kernels.py) against the numpy and
float code they replace, bit for bit: the slave's attitude (rotations.slerp) and the cut step's
transition, and the LDV's velocity, displacement, kink variance and line of sight; a float32
sample keeps the interpreted code and its float32 arithmetic."""
from __future__ import annotations

import copy

import numpy as np
import pytest

from alignment_core.geometry.rotations import floats, normalized_f, quat_mul_f, slerp
from alignment_core.navigation.history import LdvHistory, LdvRecord, SlaveHistory
from alignment_core.navigation.history_kernels import carried_k, ldv_between_k, slave_between_k
from alignment_core.navigation.strapdown import NavState

MS = 1_000_000


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and a.tobytes() == b.tobytes())
    return type(a) is type(b) and np.float64(a).tobytes() == np.float64(b).tobytes()


def _unit(rng: np.random.Generator, k: int) -> np.ndarray:
    v = rng.normal(size=k)
    return v / np.linalg.norm(v)


def _slave(rng: np.random.Generator, n: int, phi_dtype=np.float64) -> tuple[SlaveHistory, NavState, int]:
    """Five snapshots 10 ms apart turning a little each step, a transition each, and the live state."""
    hist = SlaveHistory(10**9)
    q = _unit(rng, 4)
    for k in range(5):
        s = hist.record(10 * MS * k, NavState(q_nb=q, v_n=rng.normal(size=3), lat=0.7 + 1e-7 * k, lon=0.2, h=5.0 + k))
        s.phi = (np.eye(n) + rng.normal(size=(n, n)) * 1e-3).astype(phi_dtype)
        q = q + rng.normal(size=4) * 1e-3
        q = q / np.linalg.norm(q)
    return hist, NavState(q_nb=q, v_n=rng.normal(size=3), lat=0.7, lon=0.2, h=10.0), 50 * MS


def _state_at_interpreted(hist: SlaveHistory, t_ns: int, live: NavState, t_live: int):
    """state_at's lines before the kernel: at a snapshot's time its solution; between two, slerp,
    the numpy interpolations and the cut step's I + (1 - f) (Phi - I) in numpy; then the product
    of the later steps' transitions (None if a step has none)."""
    it = hist.items
    k = max(j for j in range(len(it)) if it[j].t_ns <= t_ns)
    a = it[k]
    b = it[k + 1] if k + 1 < len(it) else SimpleSnapshot(t_live, live)
    f = (t_ns - a.t_ns) / (b.t_ns - a.t_ns)
    if f == 0.0:
        nav = a.nav()
    else:
        nav = NavState(q_nb=slerp(a.q_nb, b.q_nb, f), v_n=a.v_n + f * (b.v_n - a.v_n),
                       lat=a.lat + f * (b.lat - a.lat), lon=a.lon + f * (b.lon - a.lon), h=a.h + f * (b.h - a.h))
    phi_acc = None
    for j in range(k, len(it)):
        p = it[j].phi
        if p is None:
            return nav, None
        if j == k and f > 0.0:
            eye = np.eye(len(p))
            p = eye + (1.0 - f) * (p - eye)
        phi_acc = p if phi_acc is None else p @ phi_acc
    return nav, phi_acc


class SimpleSnapshot:
    def __init__(self, t_ns: int, nav: NavState) -> None:
        self.t_ns, self.q_nb, self.v_n, self.lat, self.lon, self.h = t_ns, nav.q_nb, nav.v_n, nav.lat, nav.lon, nav.h


@pytest.mark.parametrize('n, phi_dtype', [(15, np.float64), (19, np.float64), (15, np.float32)])
def test_the_slave_between_two_steps_is_the_interpreted_one(n, phi_dtype):
    """At 40 times between the snapshots and the live state and at each snapshot's own time: the
    attitude, velocity, position and the transition to now the same bits as slerp and numpy give
    (a float32 Phi too); with one step's transition missing, None for it from before that step."""
    rng = np.random.default_rng(n)
    hist, live, t_live = _slave(rng, n, phi_dtype)
    times = [int(t) for t in rng.integers(1, t_live, size=40)] + [10 * MS * k for k in range(5)]
    for t in times + [None] + times:
        if t is None:                       # the second pass: the fourth step without its transition
            hist.items[3].phi = None
            continue
        got_nav, got_phi = hist.state_at(t, live, t_live, 15 * MS)
        want_nav, want_phi = _state_at_interpreted(hist, t, live, t_live)
        for f in ('q_nb', 'v_n', 'lat', 'lon', 'h'):
            assert _same(getattr(got_nav, f), getattr(want_nav, f)), f
        assert (got_phi is None and want_phi is None) or _same(got_phi, want_phi)
        assert (got_phi is None) == (hist.items[3].phi is None and t < 40 * MS)
    assert hist.state_at(15 * MS, live, t_live, 5 * MS) is None          # a step longer than allowed


def _ldv(rng: np.random.Generator, beam: bool, dtype=np.float64) -> LdvHistory:
    """Eight samples 20 ms apart, a jump in the middle (a kink), invalid and moving flags mixed."""
    h = LdvHistory(10**9, 0.01)
    disp = np.zeros(3, dtype=dtype)
    for k in range(8):
        v = (rng.normal(size=3) * (5.0 if k == 4 else 0.1)).astype(dtype)
        u = _unit(rng, 3).astype(dtype) if beam else None
        h.record(LdvRecord(20 * MS * k, v, k != 6, k >= 3, disp, beam=u))
        disp = disp + v * dtype(0.02)
    return h



def test_a_correction_of_the_stored_solutions_is_the_interpreted_one():
    """Each stored solution after `correct`: the attitude the float forms give (the nav-frame
    rotation q1 q0^-1 times the stored attitude, renormalised), the velocity numpy's
    v + (v1 - v0) gives and the position moved by the changes, the same bits."""
    rng = np.random.default_rng(5)
    hist, _, _ = _slave(rng, 15)
    before = [(s.q_nb, s.v_n, s.lat, s.lon, s.h) for s in hist.items]
    q0, q1, v0, v1 = _unit(rng, 4), _unit(rng, 4), rng.normal(size=3), rng.normal(size=3)
    hist.correct(q0, q1, v0, v1, 1e-7, -2e-7, 0.3)
    cx, cy, cz, cw = floats(q0)
    q_corr = quat_mul_f(floats(q1), (-cx, -cy, -cz, cw))
    for s, (q, v, lat, lon, h) in zip(hist.items, before, strict=True):
        assert _same(s.q_nb, np.array(normalized_f(quat_mul_f(q_corr, floats(q)))))
        assert _same(s.v_n, v + (v1 - v0))
        assert (s.lat, s.lon, s.h) == (lat + 1e-7, lon + -2e-7, h + 0.3)


@pytest.mark.parametrize('beam', [False, True])
def test_the_ldv_between_two_samples_is_the_interpreted_one(beam):
    """At 60 times: every field of the record the same bits as the interpreted lines give (the
    history told that a sample was not float64), parked and moving, with and without a kink."""
    rng = np.random.default_rng(7)
    compiled = _ldv(rng, beam)
    interpreted = copy.deepcopy(compiled)
    interpreted._float64 = False
    assert compiled._float64
    for t in rng.integers(0, 140 * MS, size=60):
        got, want = compiled.at(int(t)), interpreted.at(int(t))
        assert (got is None) == (want is None)
        if got is not None:
            for f in ('t_ns', 'v_s', 'valid', 'moving', 'disp', 'var', 'beam'):
                assert _same(getattr(got, f), getattr(want, f)) or getattr(got, f) is getattr(want, f) is None, f


def test_a_float32_sample_keeps_the_interpreted_float32_interpolation():
    """A history given a float32 sample interpolates as numpy does, in float32."""
    hist = _ldv(np.random.default_rng(3), False, np.float32)
    assert not hist._float64
    rec = hist.at(50 * MS)
    assert rec is not None and rec.v_s.dtype == np.float32


def test_the_kernels_compiled_are_the_kernels_interpreted():
    rng = np.random.default_rng(11)
    qa, qb, phi = _unit(rng, 4), _unit(rng, 4), np.eye(19) + rng.normal(size=(19, 19)) * 1e-3
    va, vb = rng.normal(size=3), rng.normal(size=3)
    for a, b in zip(slave_between_k(qa, qb, va, vb, 0.3, phi), slave_between_k.py_func(qa, qb, va, vb, 0.3, phi)):
        assert _same(a, b)
    args = (_unit(rng, 4), _unit(rng, 4), rng.normal(size=3), rng.normal(size=3), _unit(rng, 4), rng.normal(size=3))
    for a, b in zip(carried_k(*args), carried_k.py_func(*args)):
        assert _same(a, b)
    args = (rng.normal(size=3), rng.normal(size=3), 0.4, rng.normal(size=3), 0.01, rng.normal(size=3), 1.0, 1e-5,
            _unit(rng, 3), _unit(rng, 3))
    for a, b in zip(ldv_between_k(*args), ldv_between_k.py_func(*args)):
        assert _same(a, b)
