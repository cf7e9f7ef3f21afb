"""Wave-frequency ship response: statistics against the frequency domain, regular waves,
linearity, symmetry, determinism, and the node (sample by sample) path against the batch.

Expected values are computed here from the spectrum, the spreading function and the RAO
called directly (sum |H|^2 S D dw dmu), not from the model's amplitude arrays.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy import signal, stats

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.ship import rao, wave_spectrum
from alignment_core.ship.config import ShipConfig
from alignment_core.ship.spectral import SpectralShipMotion
from alignment_core.units import DEG, KNOT

FS = 2.0
T4H = np.arange(int(4 * 3600 * FS) + 1) / FS
# variances need no Nyquist sampling, only a long record (convergence ~ 1 / (T dw)):
# 12 h at 0.5 Hz gives ~2 % scatter of a variance between seeds
T12H = np.arange(int(12 * 3600 * 0.5) + 1) / 0.5
DOF = ['surge', 'sway', 'heave', 'roll', 'pitch', 'yaw']


def model(seed: int = 5, **kw) -> SpectralShipMotion:
    return SpectralShipMotion(ShipConfig(mode='spectral', **kw), seed)


def expected_variance(m: SpectralShipMotion) -> np.ndarray:
    """sum_jk |H(w_jk, beta_jk, U)|^2 S(w_jk) D(mu_k) dmu dw_j, from the formulas."""
    cfg, c = m.cfg, m.comps
    n = cfg.n_directions if cfg.spreading == 'cos2' else 1
    d_dmu = 2.0 / np.pi * np.cos(c.mu) ** 2 * (np.pi / n) if n > 1 else np.ones(len(c.mu))
    s = wave_spectrum.spectrum(cfg.spectrum, c.omega, m.sea.hs_m, m.sea.tp_s)
    h = rao.ClosedFormRao()(c.omega, cfg.wave_heading_deg * DEG - c.mu, cfg.speed_kn * KNOT)
    return np.sum(np.abs(h) ** 2 * (s * d_dmu * c.d_omega)[:, None], axis=0)


@pytest.mark.parametrize('speed,heading', [(0.0, 90.0), (15.0, 120.0), (20.0, 180.0)])
def test_response_variance_matches_frequency_domain(speed, heading):
    m = model(sea_state=6, speed_kn=speed, wave_heading_deg=heading)
    x = m.wf.evaluate(T12H)[:, :6]
    var_exp = expected_variance(m)
    for i in range(6):
        if var_exp[i] < 1e-12:                       # e.g. no sway in pure head seas
            continue
        assert x[:, i].var() == pytest.approx(var_exp[i], rel=0.10), DOF[i]


def test_significant_amplitude_is_two_sigma_and_amplitudes_rayleigh():
    """Beam seas at rest, SS7: roll is narrow-band. Mean of the highest third of the crest
    amplitudes (one per zero up-crossing) = 2 sigma; the Hilbert envelope of heave, sampled
    every 30 s, is Rayleigh with the frequency-domain sigma (KS test)."""
    m = model(sea_state=7, speed_kn=0.0, wave_heading_deg=90.0)
    x = m.wf.evaluate(T4H)
    sig = np.sqrt(expected_variance(m))
    roll = x[:, 3]
    ups = np.flatnonzero((roll[:-1] < 0.0) & (roll[1:] >= 0.0))
    crests = np.array([roll[a:b].max() for a, b in zip(ups[:-1], ups[1:])])
    top = np.sort(crests)[-len(crests) // 3:]
    assert len(crests) > 500
    assert top.mean() == pytest.approx(2.0 * sig[3], rel=0.10)
    env = np.abs(signal.hilbert(x[:, 2] - x[:, 2].mean()))[::int(30 * FS)]
    p = stats.kstest(env, stats.rayleigh(scale=sig[2]).cdf).pvalue
    assert p > 0.01, p


@pytest.mark.parametrize('omega,beta_deg,speed', [(0.6, 150.0, 10.0), (0.35, 90.0, 0.0),
                                                    (1.0, 20.0, 12.0)],
                         ids=['bow-quartering', 'beam-roll-resonance', 'overtaking'])
def test_regular_wave_amplitude_and_phase(omega, beta_deg, speed):
    """One regular wave: every DOF is |H| a cos(|w_e| t + angle(H)) relative to the
    elevation at the ship a cos(|w_e| t) (least-squares fit at |w_e|)."""
    a = 1.5
    beta = beta_deg * DEG
    cfg = ShipConfig(mode='spectral', speed_kn=speed / KNOT, heading_deg=30.0)
    yaw0 = np.pi / 2 - 30.0 * DEG
    comps = wave_spectrum.regular(omega, a, chi=yaw0 - beta, phase=0.7)
    m = SpectralShipMotion(cfg, 1, comps=comps)
    k = omega**2 / wave_spectrum.G_WAVE
    we = abs(omega - k * speed * np.cos(beta))
    if beta_deg == 20.0:
        assert omega - k * speed * np.cos(beta) < 0.0           # the ship overtakes these waves
    t = np.arange(0.0, 20 * 2 * np.pi / we, 0.05)
    x = m.wf.evaluate(t)
    basis = np.stack([np.cos(we * t), -np.sin(we * t)], axis=1)  # a cos(wt + p) = c cos - s sin

    def fit(y):
        c, s = np.linalg.lstsq(basis, y, rcond=None)[0]
        return np.hypot(c, s), np.arctan2(s, c)
    amp_z, ph_z = fit(x[:, 18])
    assert amp_z == pytest.approx(a, rel=1e-9)
    h = rao.ClosedFormRao()(np.array([omega]), np.array([beta]), speed)[0]
    for i in range(6):
        if abs(h[i]) < 1e-6:
            continue
        amp, ph = fit(x[:, i])
        assert amp == pytest.approx(abs(h[i]) * a, rel=0.01), DOF[i]
        dph = np.angle(np.exp(1j * (ph - ph_z - np.angle(h[i]))))
        assert abs(dph) < 2.0 * DEG, (DOF[i], dph / DEG)
        # velocity and acceleration columns are the exact derivatives
        np.testing.assert_allclose(x[1:-1, 6 + i], np.gradient(x[:, i], t)[1:-1],
                                   atol=2e-3 * abs(h[i]) * a * we)


def test_linearity_and_calm_sea():
    t = T4H[:4000]
    x1 = model(hs_m=2.5, tp_s=10.0, wave_heading_deg=60.0).wf.evaluate(t)
    x2 = model(hs_m=5.0, tp_s=10.0, wave_heading_deg=60.0).wf.evaluate(t)
    np.testing.assert_allclose(x2.var(axis=0), 4.0 * x1.var(axis=0), rtol=1e-10)
    calm = model(sea_state=0, speed_kn=12.0)
    b = calm.batch(t)
    assert np.all(b['wf'] == 0.0)
    np.testing.assert_array_equal(b['w_b'], 0.0)
    np.testing.assert_allclose(b['euler'], np.broadcast_to([0.0, 0.0, calm.lf.yaw], b['euler'].shape))
    np.testing.assert_allclose(b['v_n'], np.broadcast_to(calm.lf.v_n, b['v_n'].shape), atol=1e-15)


def test_port_starboard_symmetry():
    """Waves from port (60 deg) and from starboard (300 deg): same statistics, mirrored
    sway, roll and yaw (equal variances, zero means)."""
    xs = [model(sea_state=6, speed_kn=12.0, wave_heading_deg=h).wf.evaluate(T12H) for h in (60.0, 300.0)]
    v = [x[:, :6].var(axis=0) for x in xs]
    np.testing.assert_allclose(v[0], v[1], rtol=0.10)
    ve = [expected_variance(model(sea_state=6, speed_kn=12.0, wave_heading_deg=h)) for h in (60.0, 300.0)]
    np.testing.assert_allclose(ve[0], ve[1], rtol=0.05)
    for x in xs:
        assert abs(x[:, 3].mean()) < 0.02 * x[:, 3].std()


def test_same_seed_same_series_other_seed_differs():
    t = T4H[:2000]
    a = model(seed=9, sea_state=5).batch(t)
    b = model(seed=9, sea_state=5).batch(t)
    c = model(seed=10, sea_state=5).batch(t)
    for k in ('p_w', 'q_nb', 'v_b', 'w_b', 'a_b', 'wdot_b'):
        np.testing.assert_array_equal(a[k], b[k])
    assert np.abs(a['w_b'] - c['w_b']).max() > 1e-4


def test_sample_by_sample_equals_batch():
    """The ship node asks for one sample at a time; the batch pipeline for all of them."""
    sc = scenario.load('deck_paper', {'ship.mode': 'spectral', 'ship.sea_state': 6, 'duration_s': 30.0,
                                'ship.wave_heading_deg': 120.0})
    batch = pipeline.ship_samples(sc)
    src = pipeline.ship_source(sc)
    for k in (0, 1, 777, 1500, len(batch) - 1):
        s = src.samples(np.array([(k * sc.dt_ns) / 1e9]), sc.t0_ns, sc.dt_ns, k)[0]
        assert s.t_ns == batch[k].t_ns
        for f in ('p_w', 'q_nb', 'v_b', 'w_b', 'a_b', 'wdot_b'):
            np.testing.assert_allclose(getattr(s, f), getattr(batch[k], f), rtol=0, atol=1e-12)


def test_motion_scale_and_heave_switch():
    t = T4H[:1000]
    base = model(sea_state=5, wave_heading_deg=120.0)
    half = SpectralShipMotion(dataclasses.replace(base.cfg, motion_scale=0.5), 5).wf.evaluate(t)
    np.testing.assert_allclose(half, 0.5 * base.wf.evaluate(t), rtol=1e-12, atol=1e-15)
    noheave = SpectralShipMotion(dataclasses.replace(base.cfg, heave=False), 5).wf.evaluate(t)
    assert np.all(noheave[:, [2, 8, 14]] == 0.0) and np.abs(noheave[:, 3]).max() > 0.0
