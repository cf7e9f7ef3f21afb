"""The closed-form standard day (the estimators' fast path) against the ambiance package and the
published US Standard Atmosphere 1976 table values."""
from __future__ import annotations

import ambiance
import numpy as np
import pytest

from alignment_core.air_data import standard_day

HEIGHTS = np.array([-400.0, 0.0, 500.0, 1000.0, 5000.0, 10999.0, 11000.0, 11001.0, 15000.0, 20000.0,
                    25000.0, 32000.0, 40000.0, 51000.0, 60000.0, 75000.0])


def test_temperature_and_pressure_match_ambiance():
    t, p = standard_day.temperature_pressure(HEIGHTS)
    ref = ambiance.Atmosphere(HEIGHTS)
    np.testing.assert_allclose(t, ref.temperature, rtol=0, atol=1e-9)
    # the package builds on the tables' six-significant-digit layer-base pressures: a rounding of
    # up to 5e-6 of p (the closed form integrates the hydrostatic equation from p0 exactly)
    np.testing.assert_allclose(p, ref.pressure, rtol=5e-6)


@pytest.mark.parametrize('h, t_k, p_pa', [(1000.0, 281.65, 89875.0), (11000.0, 216.77, 22700.0)])
def test_published_table_values(h, t_k, p_pa):
    """US Standard Atmosphere 1976, geometric heights: 1 km 281.651 K 8.9876e4 Pa; 11 km (geometric:
    geopotential 10 981 m) 216.774 K 2.2700e4 Pa."""
    t, p = standard_day.temperature_pressure(h)
    assert float(t) == pytest.approx(t_k, abs=0.01)
    assert float(p) == pytest.approx(p_pa, rel=1e-4)


def test_pressure_altitude_inverts_and_matches_the_geopotential_table():
    _, p = standard_day.temperature_pressure(HEIGHTS)
    H, t_at = standard_day.pressure_altitude(p)
    ref = ambiance.Atmosphere(HEIGHTS)
    np.testing.assert_allclose(H, ref.H, atol=1e-6)
    np.testing.assert_allclose(t_at, ref.temperature, atol=1e-9)
    # the tropopause: geopotential 11 km is 22 632.06 Pa (the table's layer-base pressure)
    assert float(standard_day.pressure_altitude(22632.06)[0]) == pytest.approx(11000.0, abs=0.05)


def test_day_pressure_obeys_the_hydrostatic_equation_of_its_temperature():
    """d ln p / dH = -g0 / (R (T_std(H) + dT)) (central differences in geopotential height), p(0) = p0,
    and dT = 0 is the standard day of ambiance."""
    from alignment_core.air_data.atmosphere import G0, P0, R_AIR, geometric_height
    H = np.array([500.0, 5000.0, 10000.0, 15000.0, 25000.0, 40000.0])
    dH = 1.0
    for dt in (-15.0, 0.0, 8.0):
        up, down = (standard_day.day_pressure(geometric_height(H + s), [dt])[0] for s in (dH, -dH))
        t_std, _ = standard_day.temperature_pressure(geometric_height(H))
        np.testing.assert_allclose((np.log(up) - np.log(down)) / (2 * dH), -G0 / (R_AIR * (t_std + dt)), rtol=1e-7)
        assert float(standard_day.day_pressure(0.0, [dt])[0, 0]) == pytest.approx(P0, rel=1e-15)
    np.testing.assert_allclose(standard_day.day_pressure(HEIGHTS, [0.0])[0], ambiance.Atmosphere(HEIGHTS).pressure,
                               rtol=5e-6)
