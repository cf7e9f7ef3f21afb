"""The reference a master sample gives the slave (estimation/matching.py)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.estimation.reference_force import SpotAcceleration
from alignment_core.estimation.reference_velocity import (
    DISPLACEMENT,
    SURVEYED,
    SURVEYED_CORRECTED,
    reference_and_fit,
    reference_velocities,
)


def test_reference_velocities_are_the_rigid_body_velocity_of_the_spot():
    """A point at lever arm r on a body turning at w_b moves at v_b + w_b x r (plus the LDV's
    relative velocity), in nav axes through C_m: against scipy's rotation matrix and numpy's
    cross product. The lever arm is the deck displacement alone, after the surveyed spot, or
    after the spot and its correction, with numpy's sums; a beam and the body rate are rotated into
    nav axes by C_m.
    The compiled kernel equals its interpreted form bit for bit."""
    rng = np.random.default_rng(5)
    for k in range(60):
        q = Rotation.random(random_state=rng).as_quat()
        w_b, v_b = rng.normal(0.0, 0.05, 3), rng.normal(0.0, 10.0, 3)
        r0, dr, disp, v_rel = rng.normal(0.0, 50.0, 3), rng.normal(0.0, 0.1, 3), rng.normal(0.0, 5.0, 3), \
            rng.normal(0.0, 1.0, 3)
        arm = (DISPLACEMENT, SURVEYED, SURVEYED_CORRECTED)[k % 3]
        beam = rng.normal(0.0, 1.0, 3) if k % 2 else np.empty(0)
        args = (q, w_b, v_b, r0, dr, disp, arm, v_rel, beam)
        c_m, r, u_n, v_ref, beam_n, w_n = reference_velocities(*args)
        r_true = (disp, r0 + disp, r0 + dr + disp)[arm]
        assert r.tobytes() == r_true.tobytes() and r is not disp
        c_true = Rotation.from_quat(q).as_matrix()
        u_true = c_true @ (np.cross(w_b, r_true) + v_rel)
        np.testing.assert_allclose(c_m, c_true, rtol=0.0, atol=1e-15)
        np.testing.assert_allclose(u_n, u_true, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(v_ref, c_true @ v_b + u_true, rtol=0.0, atol=1e-12)
        if k % 2:
            np.testing.assert_allclose(beam_n, c_true @ beam, rtol=0.0, atol=1e-15)
            assert beam_n.tobytes() == (c_m @ beam).tobytes()          # numpy's product, as the engine had it
        else:
            assert beam_n.shape == (0,)
        np.testing.assert_allclose(w_n, c_true @ w_b, rtol=0.0, atol=1e-15)
        assert w_n.tobytes() == (c_m @ w_b).tobytes()                  # numpy's product, as the delay state had it
        for got, want in zip((c_m, r, u_n, v_ref, beam_n, w_n), reference_velocities.py_func(*args), strict=True):
            assert got.tobytes() == want.tobytes()


@pytest.mark.filterwarnings('ignore::numba.core.errors.NumbaPerformanceWarning')   # the kernel copies the odd layouts
def test_the_delay_states_nav_rate_is_numpys_product_whatever_the_layout():
    """The delay state's C_m w_b: the reference kernel's (BLAS's gemv, as numpy's product of
    contiguous operands) where numpy's product would be BLAS's, numpy's own otherwise (a reversed
    or unaligned w_b, which numpy multiplies without BLAS): numpy's numbers in every layout."""
    from alignment_core.estimation.config import FilterConfig
    from alignment_core.estimation.matching import Matcher
    from alignment_core.estimation.models import make_model
    from alignment_core.estimation.outputs import Counters
    from alignment_core.samples import MasterSample
    cfg = FilterConfig(master_delay_state=True)
    matcher = Matcher(cfg, make_model(cfg), 100.0, int(0.3e9), Counters())
    rng = np.random.default_rng(9)
    raw = np.empty(3 * 8 + 1, dtype=np.uint8)[1:].view(np.float64)        # unaligned
    for k in range(300):
        w = rng.normal(0.0, 0.05, 3)
        raw[:] = w
        for w_b in (w.copy(), w[::-1].copy()[::-1], np.r_[w, w][::2][:3], raw):
            q = Rotation.random(random_state=rng).as_quat()
            m = MasterSample(t_ns=10_000_000 * (k + 1), p_w=np.zeros(3), q_nb=q, v_b=rng.normal(0.0, 5.0, 3), w_b=w_b)
            ref = matcher.reference(m, None, np.zeros(3))
            w_n = matcher.extras(None, m.t_ns, m, ref)[0]
            assert w_n.tobytes() == (ref.c_m @ w_b).tobytes()


def test_the_reference_with_the_spot_fit_is_the_two_calls():
    """reference_and_fit against reference_velocities then SpotAcceleration.add with the
    reference's C_m and arm, sample by sample through a window that fills, an arm estimated
    (moving) then still, a repeated stamp and a gap (clear): every reference array, and the spot's
    acceleration after each sample, bit for bit."""
    rng = np.random.default_rng(8)
    one, two = SpotAcceleration(0.5), SpotAcceleration(0.5)
    r0, dr = rng.normal(0.0, 30.0, 3), np.zeros(3)
    t, fitted = 0, 0
    for k in range(200):
        if k == 120:
            one.clear()
            two.clear()
        if k < 80:
            dr = dr + rng.normal(0.0, 0.01, 3)
        t = t if k % 41 == 7 else t + int(rng.integers(15_000_000, 25_000_000))
        q = Rotation.from_rotvec(rng.normal(0.0, 0.05, 3)).as_quat()
        args = (q, rng.normal(0.0, 0.05, 3), rng.normal(0.0, 1.0, 3), r0, dr, rng.normal(0.0, 0.01, 3),
                SURVEYED_CORRECTED, rng.normal(0.0, 0.1, 3), rng.normal(0.0, 1.0, 3))
        want = reference_velocities(*args)
        one.add(t, want[0], args[2], args[1], want[1])
        *got, start, ok, slope = reference_and_fit(*args, *two.buffers(), t)
        two.take(start, ok, slope)
        for g, w in zip(got, want, strict=True):
            assert g.tobytes() == w.tobytes()
        a, b = one.acceleration(), two.acceleration()
        assert (a is None) == (b is None) and (a is None or a.tobytes() == b.tobytes())
        fitted += a is not None
    assert 100 < fitted < 190
