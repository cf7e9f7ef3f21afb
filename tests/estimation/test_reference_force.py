"""The error model's specific force from the reference (filter.specific_force: reference,
estimation/reference_force.py).

The covariance of a Kalman filter on a linear model does not depend on the data: linearised
about the true trajectory, the velocity-matching model's F holds the true specific force, the
true attitude only in the bias couplings (isotropic biases: invariant under a constant rotation
of the body axes) and H the beam's direction, all independent of how far off the slave starts.
So the heading sigma after a parked alignment must not depend on the aircraft's mounting error.
With the slave's own specific force in F it does: its horizontal part carries g x the slave's
tilt error, a quantity the filter treats as known while its own roll sigma is tens of arcmin on
a beam along x, and the heading is credited with information it does not have (docs/carrier.md).
"""
from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.reference_force import SpotAcceleration, reference_specific_force, spot_slope
from alignment_core.geometry.rotations import cross
from alignment_core.units import ARCMIN
from alignment_core.validation import ConfigError

# deck's ship, beam LDV and filter, without the pieces that are not at issue here
PLAIN = {'duration_s': 30.0, 'aircraft.gear.enabled': False, 'aircraft.flexure.enabled': False,
         'filter.lever_arm_states': False, 'aircraft.lever_arm_survey_sigma_m': 0.0,
         'master.model': 'constant', 'master.rate_hz': 100.0, 'master.latency_s': 0.0,
         'master.latency_jitter_s': 0.0, 'filter.master_delay_state': False}


def _heading_sigma(force: str, roll_mounting_arcmin: float) -> float:
    sc = scenario.load('deck', {**PLAIN, 'filter.specific_force': force,
                                        'aircraft.misalignment_arcmin': [roll_mounting_arcmin, 0.0, 0.0]}, seed=2)
    return float(pipeline.run(sc, keep_truth=False).estimates[-1].misalignment_sigma[2] / ARCMIN)


def test_heading_sigma_does_not_depend_on_the_mounting_error_with_the_reference_force():
    # +-45' of roll: the slave's f^n differs by g x 90' = 0.26 m/s^2 across the beam, 3-6x the
    # carrier's horizontal acceleration; the linearised model's covariance is the same for both
    up, down = _heading_sigma('reference', 45.0), _heading_sigma('reference', -45.0)
    assert abs(up - down) < 0.02 * up
    # the slave's own specific force: the sigma follows the realised tilt error (the defect)
    up, down = _heading_sigma('slave', 45.0), _heading_sigma('slave', -45.0)
    assert abs(up - down) > 0.05 * max(up, down)


def test_spot_acceleration_is_exact_for_a_quadratic_velocity():
    # v(t) = v0 + a t + j t^2 / 2: dv/dt at the newest sample t_end is a + j t_end, exactly
    acc = SpotAcceleration(1.0)
    v0, a, j = np.array([10.0, -3.0, 0.2]), np.array([0.05, -0.02, 0.3]), np.array([0.01, 0.04, -0.02])
    t_end = 0.0
    for k in range(40):                      # 0.78 s at 50 Hz: below 0.8 of the window, no value
        t_end = 0.02 * k
        acc.add(int(round(t_end * 1e9)), np.eye(3), v0 + a * t_end + 0.5 * j * t_end ** 2, np.zeros(3), np.zeros(3))
    assert acc.acceleration() is None
    for k in range(40, 120):
        t_end = 0.02 * k
        acc.add(int(round(t_end * 1e9)), np.eye(3), v0 + a * t_end + 0.5 * j * t_end ** 2, np.zeros(3), np.zeros(3))
    np.testing.assert_allclose(acc.acceleration(), a + j * t_end, atol=1e-9)
    acc.clear()
    assert acc.acceleration() is None


def test_reference_specific_force_is_the_spot_acceleration_plus_coriolis_horizontally():
    # ENU at 45 deg N, 10 m/s north: (2 w_ie) x v has an east part -2 w_ie sin(lat) v_N... (closed form)
    w_e = 7.292115e-5
    lat = np.radians(45.0)
    w_ie = np.array([0.0, w_e * np.cos(lat), w_e * np.sin(lat)])
    v = np.array([0.0, 10.0, 0.0])
    f = reference_specific_force(np.array([0.3, -0.2, 9.8]), np.array([0.01, 0.02, 0.5]), v, w_ie, np.zeros(3))
    # (2 w_ie x v)_E = 2 (w_N v_U - w_U v_N) = -2 w_e sin(lat) 10; _N = 2 (w_U v_E - w_E v_U) = 0
    np.testing.assert_allclose(f, [0.01 - 2 * w_e * np.sin(lat) * 10.0, 0.02, 9.8], atol=1e-12)


def test_reference_specific_force_gives_numpys_bits():
    """The Python-float form against numpy's (the form it replaced), over random inputs."""
    rng = np.random.default_rng(9)
    for _ in range(500):
        f_n, a, v, w_ie, w_en = (rng.normal(size=3) * s for s in (9.8, 0.5, 20.0, 7e-5, 3e-6))
        want = np.array(f_n, dtype=float)
        want[0:2] = (a + np.cross(2.0 * w_ie + w_en, v))[0:2]
        got = reference_specific_force(f_n, a, v, w_ie, w_en)
        assert got.dtype == np.float64 and got.tobytes() == want.tobytes()


def test_reference_force_options_are_validated():
    with pytest.raises(ConfigError, match='specific_force'):
        scenario.load('deck', {'filter.specific_force': 'master'})
    with pytest.raises(ConfigError, match='reference_force_window_s'):
        scenario.load('deck', {'filter.reference_force_window_s': 0.0})
    with pytest.raises(ConfigError, match='specific_force reference'):
        scenario.load('seed001', {'filter.specific_force': 'reference'})


def test_spot_acceleration_takes_the_lever_arm_of_the_newest_sample():
    # a ship turning at a constant rate w about up, at rest otherwise: the spot at r moves on a circle,
    # v = C(t) (w x r) and a = C(t) (w x (w x r)), the centripetal -w^2 r_h (closed form)
    w = 0.05
    r = np.array([40.0, -10.0, 15.0])
    acc = SpotAcceleration(1.0)
    t_end = 0.0
    for k in range(51):
        t_end = 0.02 * k
        c, s = np.cos(w * t_end), np.sin(w * t_end)
        c_m = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        # an older, wrong lever arm before the last sample: the fit uses the newest one only
        acc.add(int(round(t_end * 1e9)), c_m, np.zeros(3), np.array([0.0, 0.0, w]), r if k == 50 else 2.0 * r)
    expected = c_m @ np.cross([0.0, 0.0, w], np.cross([0.0, 0.0, w], r))
    # the quadratic fit's truncation: a cubic c t^3 over [-T, 0] fits with the end slope -0.6 c T^2
    # (its least-squares projection), so 0.1 |v'''| T^2 = 0.1 w^4 |r_h| T^2 = 2.6e-5 m/s^2 at T = 1 s
    err = np.linalg.norm(acc.acceleration() - expected)
    assert err < 0.1 * w ** 4 * np.linalg.norm(r[:2]) * 1.1


def test_spot_acceleration_over_a_long_run_with_a_moving_arm_and_a_gap():
    # the turning ship of the test above for 30 s of 50 Hz samples (the window slides, its buffer
    # is compacted and grown many times over), the arm moving at every sample for 15 s then fixed
    # (rows recomputed, then only the new ones), a gap (clear) at 12 s: at every sample once the
    # window is full, the centripetal acceleration of the newest arm within the quadratic fit's
    # truncation (above); None for 0.8 s of samples after the gap
    w, window = 0.05, 1.0
    acc = SpotAcceleration(window)
    last_clear = 0.0
    checked = 0
    for k in range(1501):
        t = 0.02 * k
        if k == 600:
            acc.clear()
            last_clear = t
        c, s = np.cos(w * t), np.sin(w * t)
        c_m = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        r = np.array([40.0 + 0.01 * min(k, 750), -10.0, 15.0])
        acc.add(int(round(t * 1e9)), c_m, np.zeros(3), np.array([0.0, 0.0, w]), r)
        got = acc.acceleration()
        if t - last_clear < 0.8 * window - 1e-9:
            assert got is None
            continue
        assert got is not None
        expected = c_m @ np.cross([0.0, 0.0, w], np.cross([0.0, 0.0, w], r))
        assert np.linalg.norm(got - expected) < 0.1 * w ** 4 * np.linalg.norm(r[:2]) * 1.1
        checked += 1
    assert checked > 1300


def _vector_ldv_delay(acceleration: str) -> tuple[float, float]:
    """deck with a vector LDV, the aircraft on its gear (the LDV flags it creeping, so the
    delay's column is taken as moving), 30 ms of master latency not told: the delay estimate and
    its sigma (s) after 30 s."""
    sc = scenario.load('deck', {'duration_s': 30.0, 'ldv.mode': 'vector', 'master.latency_jitter_s': 0.0,
                                        'filter.specific_force': 'slave', 'filter.delay_acceleration': acceleration},
                       seed=2)
    al = pipeline.align(sc, pipeline.simulate(sc))
    k = al.state_labels.index('master_delay_s')
    e = al.outputs[-1]
    return float(e.state[k]), float(e.sigma[k])


def test_the_delay_column_from_the_master_fit_finds_the_latency():
    # the true delay is the master's 30 ms (no jitter); the column from two master samples 20 ms apart
    # carries their 1 mm/s velocity noise as 0.07 m/s^2, as large as the deck's acceleration, and the
    # estimate is pulled toward zero (errors in the regressor)
    dt, sig = _vector_ldv_delay('reference')
    assert abs(dt - 0.030) < 3.0 * sig and sig < 0.005
    dt, sig = _vector_ldv_delay('slave')
    assert 0.030 - dt > 5.0 * sig


def _exact_slope(tau: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The least-squares quadratic's slope at tau = 0 (3,) in rational arithmetic on the same
    floats: the normal equations A^T A c = A^T y solved by Cramer's rule, exactly."""
    tf = [Fraction(float(v)) for v in tau]
    cols = [[Fraction(1)] * len(tf), tf, [v * v for v in tf]]
    ata = [[sum(a * b for a, b in zip(cols[i], cols[j])) for j in range(3)] for i in range(3)]

    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    out = []
    for axis in range(3):
        yf = [Fraction(float(v)) for v in y[:, axis]]
        atb = [sum(a * b for a, b in zip(cols[i], yf)) for i in range(3)]
        m = [[atb[i] if j == 1 else ata[i][j] for j in range(3)] for i in range(3)]
        out.append(float(det(m) / det(ata)))
    return np.array(out)


def test_the_fit_is_the_exact_least_squares_slope():
    # random windows of random sizes: the rows are C (v + w x r) (numpy's stacked products, to
    # rounding), and the slope is the exact least-squares one of those rows to 1e-14 of |y| / T
    # (the orthogonal-polynomial fit is backward stable in a basis of condition ~1; LAPACK's
    # gelsd on [1, tau, tau^2] is off by up to 8e-14 here); compiled and interpreted alike
    rng = np.random.default_rng(5)
    for _ in range(40):
        n = int(rng.integers(4, 80))
        t = np.cumsum(rng.integers(15_000_000, 25_000_000, n)).astype(np.int64)
        c = np.array([Rotation.from_rotvec(v).as_matrix() for v in rng.normal(0.0, 0.3, (n, 3))])
        vw = rng.normal(0.0, 1.0, (n, 2, 3)) * [[5.0], [0.05]]
        r = rng.normal(0.0, 20.0, 3)
        x = vw[:, 0] + cross(vw[:, 1], r)
        want_rows = np.matmul(c, x[:, :, None])[:, :, 0]
        rows = np.zeros((n, 3))
        got = spot_slope(t, c, vw, rows, r, 0, 0, n)
        np.testing.assert_allclose(rows, want_rows, rtol=0.0, atol=4 * np.finfo(float).eps * np.abs(x).max() * 3)
        tau = (t - t[-1]) * 1e-9
        scale = np.abs(rows).max() / (tau[-1] - tau[0])
        np.testing.assert_allclose(got, _exact_slope(tau, rows), rtol=0.0, atol=1e-14 * scale)
        assert np.array_equal(spot_slope.py_func(t, c, vw, np.zeros((n, 3)), r, 0, 0, n), got)


def test_a_master_sample_not_after_the_newest_is_ignored():
    # samples at 50 Hz until the window is full; then one at the newest time and one older, each
    # with another velocity and lever arm: the fit is unchanged, bit for bit, and the next new
    # sample still enters it
    acc = SpotAcceleration(1.0)
    c_m = np.eye(3)
    for k in range(60):
        acc.add(20_000_000 * k, c_m, np.array([0.1 * k, 0.0, 0.0]), np.zeros(3), np.array([1.0, 2.0, 3.0]))
    before = acc.acceleration()
    assert before is not None
    for t in (20_000_000 * 59, 20_000_000 * 30):
        acc.add(t, c_m, np.array([50.0, 50.0, 50.0]), np.ones(3), np.array([9.0, 9.0, 9.0]))
        got = acc.acceleration()
        assert got is not None and np.array_equal(got, before)
    acc.add(20_000_000 * 60, c_m, np.array([6.0 + 5.0, 0.0, 0.0]), np.zeros(3), np.array([1.0, 2.0, 3.0]))
    after = acc.acceleration()
    assert after is not None and after[0] > before[0]


def test_the_fit_made_as_each_sample_enters_is_the_fit_of_its_window_made_afresh():
    """The fit is made when a sample enters, its rows kept while the arm stays: after every
    sample of a long run (the arm still for a while, then moving, repeated stamps, a gap, the
    buffer compacted and grown), bit for bit the slope of the window's samples with the newest
    arm, rows and fit made afresh (spot_slope on new arrays); None until the window fills."""
    rng = np.random.default_rng(11)
    window_ns = 1_000_000_000
    acc = SpotAcceleration(window_ns * 1e-9)
    kept: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]] = []
    t, checked = 0, 0
    r = np.array([40.0, -10.0, 15.0])
    for k in range(700):
        if k == 350:
            acc.clear()
            kept.clear()
        t_k = t if k % 97 == 5 else t + int(rng.integers(15_000_000, 25_000_000))   # a repeated stamp: ignored
        if k > 200 and k % 3:
            r = r + rng.normal(0.0, 0.01, 3)
        c_m = Rotation.from_rotvec(rng.normal(0.0, 0.05, 3)).as_matrix()
        v_b, w_b = rng.normal(0.0, 1.0, 3), rng.normal(0.0, 0.02, 3)
        acc.add(t_k, c_m, v_b, w_b, r)
        if not kept or t_k > kept[-1][0]:
            kept.append((t_k, c_m, v_b, w_b))
            arm = r
        t = max(t, t_k)
        window = [s for s in kept if kept[-1][0] - s[0] <= window_ns]
        got = acc.acceleration()
        if len(window) < 4 or window[-1][0] - window[0][0] < 0.8 * window_ns:
            assert got is None
            continue
        n = len(window)
        ts = np.array([s[0] for s in window], dtype=np.int64)
        cs = np.array([s[1] for s in window])
        vw = np.array([[s[2], s[3]] for s in window])
        want = spot_slope(ts, cs, vw, np.zeros((n, 3)), arm, 0, 0, n)
        assert got is not None and got.tobytes() == want.tobytes()
        checked += 1
    assert checked > 500


@pytest.mark.parametrize('arm', [2.0, np.float64(2.0), np.ones(1), np.ones(4), np.ones((3, 1)), np.empty(0)])
def test_a_lever_arm_that_is_no_3_vector_is_refused(arm):
    """The fit's kernel reads three components of the arm (and checks no bounds): any other shape
    is refused with a clear error, and the fit is left as it was."""
    acc = SpotAcceleration(1.0)
    for k in range(60):
        acc.add(20_000_000 * k, np.eye(3), np.array([0.1 * k, 0.0, 0.0]), np.zeros(3), np.array([1.0, 2.0, 3.0]))
    before = acc.acceleration()
    with pytest.raises(ValueError, match='3-vector'):
        acc.add(20_000_000 * 60, np.eye(3), np.zeros(3), np.zeros(3), arm)
    assert acc.acceleration() is before
