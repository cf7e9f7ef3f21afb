"""Impact pressure against its closed forms, written out here for gamma = 1.4:
subsonic qc/p = (1 + 0.2 M^2)^3.5 - 1, supersonic (Rayleigh pitot) (qc + p)/p = 166.92158 M^7 /
(7 M^2 - 1)^2.5; the values M 0.5 -> 0.186213, M 2 -> 4.640441, M 7 -> 62.5526, both branches
0.892929 at M = 1 (six printed digits); the inverse; CAS at sea level is TAS."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.air_data import pitot


def subsonic(m):
    return (1.0 + 0.2 * m**2) ** 3.5 - 1.0


def rayleigh(m):
    return 166.92158 * m**7 / (7.0 * m**2 - 1.0) ** 2.5 - 1.0


@pytest.mark.parametrize('mach, ratio', [(0.5, 0.186213), (2.0, 4.640441), (7.0, 62.5526), (1.0, 0.892929)])
def test_published_values(mach, ratio):
    assert float(pitot.impact_pressure_ratio(mach)) == pytest.approx(ratio, abs=6e-7 * max(1.0, ratio))


def test_both_branches_meet_at_mach_one():
    assert subsonic(1.0) == pytest.approx(0.892929, abs=5e-7)
    assert rayleigh(1.0) == pytest.approx(0.892929, abs=5e-7)
    below, above = pitot.impact_pressure_ratio_slope(1.0 - 1e-12), pitot.impact_pressure_ratio_slope(1.0)
    assert float(below) == pytest.approx(1.4 * 1.2**2.5, rel=1e-9)          # d/dM of the subsonic form
    assert float(above) == pytest.approx(float(below), rel=1e-6)


def test_against_the_closed_forms():
    sub = np.linspace(0.0, 0.999, 200)
    sup = np.linspace(1.0, 12.0, 300)
    np.testing.assert_allclose(pitot.impact_pressure_ratio(sub), subsonic(sub), rtol=1e-13, atol=1e-15)
    # 166.92158 is the constant ((gamma+1)^2/2)^3.5 / (gamma+1) to eight digits
    np.testing.assert_allclose(pitot.impact_pressure_ratio(sup), rayleigh(sup), rtol=5e-8)
    np.testing.assert_allclose(pitot.impact_pressure(0.5, 5e4), 5e4 * subsonic(0.5), rtol=1e-13)


def test_slope_against_central_differences():
    m = np.array([0.05, 0.3, 0.8, 0.99, 1.01, 1.5, 3.0, 7.0, 15.0])
    h = 1e-6
    fd = (pitot.impact_pressure_ratio(m + h) - pitot.impact_pressure_ratio(m - h)) / (2 * h)
    np.testing.assert_allclose(pitot.impact_pressure_ratio_slope(m), fd, rtol=1e-7)


def test_inverse_round_trip():
    m = np.concatenate([np.linspace(0.0, 0.999, 100), [1.0], np.linspace(1.001, 25.0, 200)])
    np.testing.assert_allclose(pitot.mach_from_impact_ratio(pitot.impact_pressure_ratio(m)), m, rtol=1e-12, atol=1e-12)
    assert pitot.mach_from_impact_ratio(np.array([[0.186213, 62.5526]])).shape == (1, 2)
    assert float(pitot.mach_from_impact_ratio(-0.01)) == 0.0
    with pytest.raises(ValueError):
        pitot.mach_from_impact_ratio(1e9)


def test_airspeeds():
    t, a0 = 223.25, np.sqrt(1.4 * 287.05287 * 288.15)
    assert float(pitot.true_airspeed(0.8, t)) == pytest.approx(0.8 * np.sqrt(1.4 * 287.05287 * t), rel=1e-14)
    assert float(pitot.mach_from_airspeed(pitot.true_airspeed(0.8, t), t)) == pytest.approx(0.8, rel=1e-14)
    assert float(pitot.dynamic_pressure(2.0, 1e4)) == pytest.approx(0.7 * 1e4 * 4.0, rel=1e-14)
    # at standard sea level CAS is TAS, sub- and supersonic
    for m in (0.3, 0.9, 1.6):
        qc = float(pitot.impact_pressure(m, 101325.0))
        assert float(pitot.calibrated_airspeed(qc)) == pytest.approx(a0 * m, rel=1e-12)
    # aloft, the subsonic CAS formula a0 sqrt(5 ((qc/p0 + 1)^(2/7) - 1))
    qc = 26436.0 * subsonic(0.8)
    assert float(pitot.calibrated_airspeed(qc)) == pytest.approx(a0 * np.sqrt(5 * ((qc / 101325 + 1) ** (2 / 7) - 1)),
                                                                  rel=1e-12)
