"""Wave synthesis and sea states (spectral ship mode).

Expected values come from the spectrum formulas integrated by scipy quadrature, the Bales
table and textbook ratios (Tz = 0.710 Tp for ITTC), not from the synthesis code.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate, signal

from alignment_core.ship import sea_state, wave_spectrum
from alignment_core.ship.config import ShipConfig
from alignment_core.ship.spectral import SpectralShipMotion
from alignment_core.validation import ConfigError

FS = 2.0                                   # Hz, plenty for waves (periods > 2.5 s)
T_LONG = np.arange(int(3 * 3600 * FS) + 1) / FS


def elevation(**kw) -> tuple[np.ndarray, SpectralShipMotion]:
    """Elevation at a ship at rest (= a fixed point) over 3 h."""
    cfg = ShipConfig(mode='spectral', speed_kn=0.0, **kw)
    m = SpectralShipMotion(cfg, seed=3)
    return m.wf.evaluate(T_LONG)[:, 18], m


def test_bales_table_and_wmo_codes():
    assert sea_state.resolve(6) == sea_state.SeaState(6, 5.0, 12.4)
    assert sea_state.resolve(3) == sea_state.SeaState(3, 0.88, 7.5)
    assert sea_state.resolve(0).hs_m == 0.0
    assert sea_state.resolve(4, hs_m=3.0).code == 5 and sea_state.resolve(4, hs_m=3.0).tp_s == 9.7
    assert sea_state.resolve(4, hs_m=3.0, tp_s=11.0).tp_s == 11.0
    assert [sea_state.wmo_code(h) for h in (0.0, 0.05, 0.3, 1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 15.0)] == list(range(10))
    with pytest.raises(ConfigError, match='WMO code 0-9'):
        sea_state.resolve(12)


def test_monte_carlo_draw_stays_in_bin():
    rng = np.random.default_rng(0)
    for code in range(2, 9):
        lo, hi = sea_state.WMO_HS_BIN_M[code]
        _, t_lo, t_hi, _ = sea_state.BALES[code]
        draws = [sea_state.resolve(code, rng=rng) for _ in range(200)]
        hs = np.array([d.hs_m for d in draws])
        tp = np.array([d.tp_s for d in draws])
        assert np.all((hs >= lo) & (hs <= hi)) and np.all((tp >= t_lo) & (tp <= t_hi))
        assert hs.std() > 0.2 * (hi - lo) and tp.std() > 0.1 * (t_hi - t_lo)


@pytest.mark.parametrize('name', ['ittc', 'jonswap'])
def test_spectrum_m0_peak_and_tz(name):
    hs, tp = 5.0, 12.4

    def s(w):
        return wave_spectrum.spectrum(name, w, hs, tp)
    m0 = integrate.quad(s, 1e-3, 50.0, limit=400)[0]
    assert m0 == pytest.approx(hs**2 / 16.0, rel=1e-4)
    w = np.linspace(0.2, 2.0, 20001)
    assert w[np.argmax(s(w))] == pytest.approx(2 * np.pi / tp, rel=1e-3)
    if name == 'ittc':
        m2 = integrate.quad(lambda x: x**2 * s(x), 1e-3, 500.0, limit=400)[0]
        assert 2 * np.pi * np.sqrt(m0 / m2) == pytest.approx(0.710 * tp, rel=2e-3)


def test_cos2_spreading_weights():
    mu, wts, dmu = wave_spectrum.spreading_directions('cos2', 15)
    assert len(mu) == 15 and np.sum(wts) == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(wts, 2 / np.pi * np.cos(mu) ** 2 * np.pi / 15, rtol=1e-12)
    assert np.all(np.abs(mu) < np.pi / 2) and mu == pytest.approx(-mu[::-1])


@pytest.mark.parametrize('spectrum,spreading', [('ittc', 'cos2'), ('jonswap', 'none')])
def test_hs_from_elevation(spectrum, spreading):
    z, m = elevation(sea_state=6, spectrum=spectrum, spreading=spreading)
    assert len(m.comps) == (2250 if spreading == 'cos2' else 150)
    assert 4.0 * z.std() == pytest.approx(5.0, rel=0.05)
    assert abs(z.mean()) < 0.05


def test_zero_crossing_period():
    z, _ = elevation(sea_state=6, spectrum='ittc')
    ups = np.count_nonzero((z[:-1] < 0.0) & (z[1:] >= 0.0))
    tz = (T_LONG[-1] - T_LONG[0]) / ups
    assert tz == pytest.approx(0.710 * 12.4, rel=0.05)


def test_welch_psd_follows_spectrum():
    """One-sided PSD in Hz is 2 pi S(omega); compare band powers with the quadrature of S."""
    hs, tp = 5.0, 12.4
    z, _ = elevation(sea_state=6, spectrum='ittc')
    f, p = signal.welch(z, fs=FS, nperseg=2048)
    wp = 2 * np.pi / tp
    edges = np.array([0.7, 0.9, 1.1, 1.4, 2.0, 3.0]) * wp
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (2 * np.pi * f >= lo) & (2 * np.pi * f < hi)
        measured = np.sum(p[sel]) * (f[1] - f[0])
        f_lo, f_hi = f[sel][0] - 0.5 * (f[1] - f[0]), f[sel][-1] + 0.5 * (f[1] - f[0])
        expected = integrate.quad(lambda w: wave_spectrum.ittc(w, hs, tp), 2 * np.pi * f_lo, 2 * np.pi * f_hi)[0]
        assert measured == pytest.approx(expected, rel=0.15), (lo / wp, hi / wp)
    # the PSD in Hz equals 2 pi S(omega) at the peak (smoothed over 5 bins)
    k = np.argmin(np.abs(2 * np.pi * f - wp))
    assert np.mean(p[k - 2:k + 3]) == pytest.approx(
        2 * np.pi * np.mean(wave_spectrum.ittc(2 * np.pi * f[k - 2:k + 3], hs, tp)), rel=0.2)


def test_no_repetition():
    """Random frequencies inside bins: the record does not repeat at the bin spacing."""
    z, m = elevation(sea_state=5)
    dw = np.diff(np.log(np.unique(m.comps.d_omega)))
    assert dw.size > 0                                  # bins are not uniform in omega
    lag = int(round(2 * np.pi / np.min(m.comps.d_omega) * FS))   # period of a uniform grid
    n = len(z) - lag
    r = np.corrcoef(z[:n], z[lag:lag + n])[0, 1]
    assert abs(r) < 0.1
