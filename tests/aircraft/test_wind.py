"""Wind truth: MIL-F-8785C intensities and scale lengths, and the Dryden spectra of the
generated turbulence.

Spectra. One record of N = 2^18 samples at 20 Hz (3.6 h of flight; 4900 correlation times at
10 km, V = 200 m/s, L = 533.4 m), Welch with 4096-sample Hann segments at 50 % overlap: K = 127
segments, so one frequency bin scatters by sqrt(1.056 / K) = 9.1 % (1.056: the Hann overlap
correlation), and a band of m bins by about 9.1 % sqrt(1.5 / m) (neighbouring Hann bins are
correlated). Six log-spaced bands from 0.03 Hz (6 resolution bins) to 1 Hz, 5 to 140 bins
each; each band mean must lie within 5 of its standard errors
plus 2 % (aliasing below 1 Hz at 20 Hz sampling is < 1 %, Hann leakage above 5 resolution bins
< 1 %) of the closed form
    Phi_u(f) = 2 pi sigma^2 (2 L / (pi V)) / (1 + (2 pi f L / V)^2)         (one-sided, per Hz)
    Phi_v(f) = 2 pi sigma^2 (L / (pi V)) (1 + 3 (2 pi f L/V)^2) / (1 + (2 pi f L/V)^2)^2.
Intensities: the sample standard deviation of a record T long with correlation time tau has a
relative error ~ sqrt(tau / (2 T)) (~1 %); 5 % is allowed.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import welch

from alignment_core.aircraft.wind import WindConfig, WindField, dryden_parameters, linear_recurrence
from alignment_core.validation import ConfigError, build

FT, KT = 0.3048, 1852.0 / 3600.0
FS, N = 20.0, 2**18


def record(severity, height, speed, seed=21, track=0.0):
    return WindField(WindConfig(severity=severity), seed).turbulence(np.arange(N) / FS, height, speed, track)


def phi_u(f, sigma, length, speed):
    x = 2 * np.pi * f * length / speed
    return 2 * np.pi * sigma**2 * 2 * length / (np.pi * speed) / (1 + x**2)


def phi_v(f, sigma, length, speed):
    x = 2 * np.pi * f * length / speed
    return 2 * np.pi * sigma**2 * length / (np.pi * speed) * (1 + 3 * x**2) / (1 + x**2) ** 2


def check_spectrum(series, closed_form, resolution_hz):
    f, s = welch(series, fs=FS, nperseg=4096)
    edges = np.geomspace(max(6 * resolution_hz, 0.03), 1.0, 7)
    for lo, hi in zip(edges[:-1], edges[1:]):
        band = (f >= lo) & (f < hi)
        m = int(band.sum())
        assert m >= 5, (lo, hi, m)
        se = np.sqrt(1.056 / 127) * np.sqrt(1.5 / m)
        ratio = float(np.mean(s[band] / closed_form(f[band])))
        assert abs(ratio - 1.0) < 5 * se + 0.02, (lo, hi, m, ratio, se)


def test_intensity_and_scale_lengths_low_altitude():
    h = 500 * FT
    par = dryden_parameters(h, 'moderate')
    d = 0.177 + 0.000823 * 500
    sigma_w = 0.1 * 30 * KT                         # 0.1 W20, W20 = 30 kt for moderate
    assert float(par.sigma_w) == pytest.approx(sigma_w, rel=1e-5)
    assert float(par.sigma_u) == pytest.approx(sigma_w / d**0.4, rel=1e-5)
    assert float(par.sigma_u) == pytest.approx(1.9079, abs=1e-3)        # by hand: 1.5433 / 0.8089
    assert float(par.sigma_v) == float(par.sigma_u)
    assert float(par.length_w) == pytest.approx(500 * FT, rel=1e-12)
    assert float(par.length_u) == pytest.approx(500 / d**1.2 * FT, rel=1e-12)
    assert float(par.length_u) == pytest.approx(287.9, abs=0.1)        # 944.6 ft
    assert float(par.length_v) == float(par.length_u)
    light, severe = dryden_parameters(h, 'light'), dryden_parameters(h, 'severe')
    assert float(light.sigma_w) == pytest.approx(1.5 * KT, rel=1e-5)
    assert float(severe.sigma_w) == pytest.approx(4.5 * KT, rel=1e-5)
    assert float(dryden_parameters(h, 'light', w20_mps=10.0).sigma_w) == pytest.approx(1.0, rel=1e-12)


def test_intensity_and_scale_lengths_medium_and_high_altitude():
    # Figure 7 (ft/s), linear in height: moderate 25 000 ft 6.6, 35 000 ft 5.0
    h_ft = 10000.0 / FT
    par = dryden_parameters(10000.0, 'moderate')
    expect = (6.6 + (h_ft - 25000.0) / 10000.0 * (5.0 - 6.6)) * FT
    for sigma in (par.sigma_u, par.sigma_v, par.sigma_w):
        assert float(sigma) == pytest.approx(expect, rel=1e-12)
    assert float(par.sigma_u) == pytest.approx(1.6309, abs=1e-4)
    for length in (par.length_u, par.length_v, par.length_w):
        assert float(length) == pytest.approx(1750 * FT, rel=1e-12)
    assert float(dryden_parameters(20000.0, 'moderate').sigma_w) == 0.0      # moderate ends near 65 000 ft
    sev = (7.9 + (20000.0 / FT - 65000.0) / 10000.0 * (6.2 - 7.9)) * FT
    assert float(dryden_parameters(20000.0, 'severe').sigma_w) == pytest.approx(sev, rel=1e-12)
    light_5000 = (7.4 + 1250 / 3750 * (6.7 - 7.4)) * FT          # between 3750 ft (7.4) and 7500 ft (6.7)
    assert float(dryden_parameters(5000 * FT, 'light').sigma_u) == pytest.approx(light_5000, rel=1e-12)


def test_transition_between_1000_and_2000_ft():
    lo, hi, mid = (dryden_parameters(x * FT, 'severe') for x in (1000.0, 2000.0, 1500.0))
    assert float(lo.length_u) == pytest.approx(1000 * FT, rel=1e-12) and float(lo.length_w) == pytest.approx(1000 * FT)
    assert float(lo.sigma_u) == pytest.approx(0.1 * 45 * KT, rel=1e-5) == float(lo.sigma_w)
    assert float(hi.sigma_w) == pytest.approx((17.6 + 250 / 2000 * 5.4) * FT, rel=1e-12)
    for name in ('sigma_u', 'sigma_w', 'length_u', 'length_w'):
        halfway = 0.5 * (float(getattr(lo, name)) + float(getattr(hi, name)))
        assert float(getattr(mid, name)) == pytest.approx(halfway, rel=1e-12)


def test_dryden_spectra_high_altitude():
    speed = 200.0
    par = dryden_parameters(10000.0, 'moderate')
    g = record('moderate', 10000.0, speed)
    sigma, length = float(par.sigma_u), float(par.length_u)
    np.testing.assert_allclose(g.std(axis=0), sigma, rtol=0.05)
    check_spectrum(g[:, 0], lambda f: phi_u(f, sigma, length, speed), FS / 4096)
    check_spectrum(g[:, 1], lambda f: phi_v(f, sigma, length, speed), FS / 4096)
    check_spectrum(g[:, 2], lambda f: phi_v(f, sigma, length, speed), FS / 4096)


def test_dryden_spectra_low_altitude():
    # 500 ft: L_u = 288 m, L_w = 152 m, sigma_u = 1.24 sigma_w
    h, speed = 500 * FT, 70.0
    par = dryden_parameters(h, 'moderate')
    g = record('moderate', h, speed, seed=22)
    np.testing.assert_allclose(g.std(axis=0), [par.sigma_u, par.sigma_v, par.sigma_w], rtol=0.05)
    check_spectrum(g[:, 0], lambda f: phi_u(f, float(par.sigma_u), float(par.length_u), speed), FS / 4096)
    check_spectrum(g[:, 1], lambda f: phi_v(f, float(par.sigma_v), float(par.length_v), speed), FS / 4096)
    check_spectrum(g[:, 2], lambda f: phi_v(f, float(par.sigma_w), float(par.length_w), speed), FS / 4096)


def test_autocorrelation_gives_the_scale_lengths():
    # rho_u(xi) = exp(-xi/L); rho_w(xi) = (1 - xi/(2L)) exp(-xi/L): 0.368 and 0.184 at xi = L,
    # rho_w crosses zero at xi = 2 L
    speed = 200.0
    g = record('severe', 10000.0, speed, seed=23)
    lag = int(round(533.4 / speed * FS))
    for k, expect in ((0, np.exp(-1.0)), (2, 0.5 * np.exp(-1.0)), (2, 0.0)):
        x = g[:, k] - g[:, k].mean()
        step = lag if expect != 0.0 else 2 * lag
        rho = float(np.mean(x[:-step] * x[step:]) / np.var(x))
        assert rho == pytest.approx(expect, abs=0.03)


def test_climb_keeps_unit_variance_processes():
    # V and h change (L/V from 0.3 s to 5 s): the normalised turbulence stays unit variance
    t = np.arange(60000) / FS
    h = np.linspace(20.0, 3000.0, len(t))
    speed = np.linspace(60.0, 200.0, len(t))
    g = WindField(WindConfig(severity='moderate'), 24).turbulence(t, h, speed)
    par = dryden_parameters(h, 'moderate')
    for k, sigma in enumerate((par.sigma_u, par.sigma_v, par.sigma_w)):
        z = g[:, k] / sigma
        for part in np.array_split(z, 3):
            assert np.var(part) == pytest.approx(1.0, abs=0.12)


def test_reproducible_chunkable_and_rotated():
    t = np.arange(5000) / FS
    cfg = WindConfig(mean_enu_mps=(3.0, -4.0, 0.0), severity='light')
    whole = WindField(cfg, 5).wind(t, 500.0, 80.0)
    field = WindField(cfg, 5)
    parts = np.concatenate([field.wind(t[:1], 500.0, 80.0), field.wind(t[1:1234], 500.0, 80.0),
                            field.wind(t[1234:], 500.0, 80.0)])
    np.testing.assert_allclose(parts, whole, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(WindField(cfg, 5).wind(t, 500.0, 80.0), whole)
    assert not np.allclose(WindField(cfg, 6).wind(t, 500.0, 80.0), whole)
    # the track turns the (u, v) pair: ENU = Rz(track) (u, v, w)
    base = WindField(cfg, 5).turbulence(t, 500.0, 80.0, 0.0)
    turned = WindField(cfg, 5).turbulence(t, 500.0, 80.0, np.pi / 3)
    c, s = np.cos(np.pi / 3), np.sin(np.pi / 3)
    np.testing.assert_allclose(turned, base @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]]), atol=1e-12)
    with pytest.raises(ValueError):
        field.wind(t[:3], 500.0, 80.0)            # earlier than the last sample


def test_no_turbulence_is_the_mean_wind():
    t = np.arange(100) / FS
    w = WindField(WindConfig(mean_enu_mps=(5.0, 1.0, -0.5)), 1).wind(t, 1000.0, 100.0)
    np.testing.assert_array_equal(w, np.tile([5.0, 1.0, -0.5], (100, 1)))
    with pytest.raises(ConfigError):
        build(WindConfig, {'severity': 'extreme'})


def test_linear_recurrence_matches_a_loop():
    rng = np.random.default_rng(0)
    for n, chunk in ((1, 128), (2, 128), (2, 7), (3, 64)):
        phi, w, x0 = rng.uniform(-0.6, 0.6, (1000, n, n)), rng.standard_normal((1000, n)), rng.standard_normal(n)
        x, expect = x0, []
        for k in range(1000):
            x = phi[k] @ x + w[k]
            expect.append(x)
        np.testing.assert_allclose(linear_recurrence(phi, w, x0, chunk), expect, atol=1e-12)
