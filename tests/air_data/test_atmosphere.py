"""The atmosphere against independent references.

- Standard day: fluids.ATMOSPHERE_1976 (its own implementation of the 1976 standard) over
  0-32 km: T identical; speed of sound within 1e-6; pressure and density within 5e-6: the gas
  constants differ by 8.2e-7 (fluids R*/M0 = 287.0531, ICAO 287.05287), which moves ln p by
  ln(p0/p) dR/R, 3.8e-6 at 32 km. The ambiance package's own pressure agrees within 2e-6: its
  six-digit layer-base pressures (22 632.0 for 22 632.04 at 11 km) are its only difference.
- Published ICAO / 1976 table values, by geopotential altitude: 1 km 281.65 K, 336.43 m/s,
  89 875 Pa; 11 km 22 632 Pa; 20 km 5474.9 Pa (and 5529.3 Pa at 20 km geometric).
- Non-standard day (T_std + dT, sea-level p0 + dp0, hydrostatic): below 11 km the closed form
  p = (p0 + dp0) (1 - 0.0065 H / (T0 + dT))^(g0 / (0.0065 R)); in the isothermal layer
  p(20 km) / p(11 km) = exp(-g0 9000 / (R (216.65 + dT))); everywhere to 32 km a numerical
  integration of d ln p / dH = -g0 / (R (T_fluids(H) + dT)); with dT = 0 the ratio to the
  standard day is exactly 1 + dp0/p0.
"""
from __future__ import annotations

import ambiance
import fluids
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from alignment_core.air_data.atmosphere import (
    Atmosphere,
    DayOffsets,
    geometric_height,
    geopotential_height,
    pressure_altitude,
    pressure_altitude_slope,
)
from alignment_core.validation import ConfigError, build

R, G0, P0, T0 = 287.05287, 9.80665, 101325.0, 288.15


def test_standard_day_matches_fluids_1976_to_32_km():
    h = np.linspace(0.0, 32000.0, 161)
    atm = Atmosphere(h)
    ref = [fluids.ATMOSPHERE_1976(float(x)) for x in h]
    np.testing.assert_allclose(atm.temperature, [r.T for r in ref], rtol=1e-12)
    np.testing.assert_allclose(atm.pressure, [r.P for r in ref], rtol=5e-6)
    np.testing.assert_allclose(atm.density, [r.rho for r in ref], rtol=5e-6)
    np.testing.assert_allclose(atm.pressure, ambiance.Atmosphere(h).pressure, rtol=2e-6)
    np.testing.assert_allclose(atm.speed_of_sound, [r.v_sonic for r in ref], rtol=1e-6)
    np.testing.assert_allclose(atm.geopotential, [r.H for r in ref], rtol=1e-12)


def test_published_table_values_by_geopotential_altitude():
    atm = Atmosphere(geometric_height(np.array([1000.0, 11000.0, 20000.0])))
    assert atm.temperature[0] == pytest.approx(281.65, abs=0.005)
    assert atm.speed_of_sound[0] == pytest.approx(336.43, abs=0.005)
    assert atm.pressure[0] == pytest.approx(89875.0, abs=0.5)
    assert atm.pressure[1] == pytest.approx(22632.0, abs=0.5)
    assert atm.pressure[2] == pytest.approx(5474.9, abs=0.05)
    assert float(Atmosphere(20000.0).pressure) == pytest.approx(5529.3, abs=0.05)     # geometric 20 km


def test_shapes_follow_the_input():
    assert Atmosphere(1000.0).pressure.shape == ()
    assert Atmosphere(np.zeros((2, 3))).temperature.shape == (2, 3)
    assert pressure_altitude(np.full((4, 1), 5e4)).shape == (4, 1)


@pytest.mark.parametrize('day', [DayOffsets(), DayOffsets(15.0, 0.0), DayOffsets(-20.0, -1500.0),
                                 DayOffsets(0.0, 800.0)])
def test_inverse_round_trip(day):
    h = np.linspace(-1000.0, 32000.0, 331)
    back = Atmosphere.from_pressure(Atmosphere(h, day).pressure, day)
    np.testing.assert_allclose(back.h, h, atol=1e-6)
    np.testing.assert_allclose(back.temperature, Atmosphere(h, day).temperature, rtol=1e-12)


def test_pressure_altitude_is_the_standard_geopotential_height():
    H = np.linspace(0.0, 30000.0, 61)
    np.testing.assert_allclose(pressure_altitude(Atmosphere(geometric_height(H)).pressure), H, atol=1e-6)
    np.testing.assert_allclose(geopotential_height(geometric_height(H)), H, atol=1e-8)
    # geometric 20 km is 62.9 m higher than 20 km geopotential (r0 H / (r0 - H) - H)
    assert float(geometric_height(20000.0)) - 20000.0 == pytest.approx(20000.0**2 / (6356766.0 - 20000.0), rel=1e-12)


def test_pressure_altitude_slope():
    # dH/dp = -R T / (g0 p): 0.0917 m/Pa at 1 km (281.65 K, 89 875 Pa), 1.158 m/Pa at 20 km
    assert float(pressure_altitude_slope(89874.6)) == pytest.approx(-R * 281.65 / (G0 * 89874.6), rel=1e-5)
    assert float(pressure_altitude_slope(5474.9)) == pytest.approx(-R * 216.65 / (G0 * 5474.9), rel=1e-5)
    assert float(pressure_altitude_slope(89874.6)) == pytest.approx(-0.092, abs=5e-4)


@pytest.mark.parametrize('dt, dp0', [(15.0, 0.0), (-25.0, 0.0), (10.0, -1200.0), (-5.0, 2000.0)])
def test_non_standard_day_in_the_troposphere_closed_form(dt, dp0):
    day = DayOffsets(dt, dp0)
    H = np.linspace(0.0, 11000.0, 45)
    atm = Atmosphere(geometric_height(H), day)
    expect = (P0 + dp0) * (1.0 - 0.0065 * H / (T0 + dt)) ** (G0 / (0.0065 * R))
    np.testing.assert_allclose(atm.pressure, expect, rtol=1e-9)
    np.testing.assert_allclose(atm.temperature, T0 - 0.0065 * H + dt, rtol=1e-12)
    assert np.all(np.diff(atm.pressure) < 0.0)


@pytest.mark.parametrize('dt', [15.0, -25.0])
def test_non_standard_day_isothermal_layer(dt):
    atm = Atmosphere(geometric_height(np.array([11000.0, 20000.0])), DayOffsets(dt, 0.0))
    assert atm.pressure[1] / atm.pressure[0] == pytest.approx(np.exp(-G0 * 9000.0 / (R * (216.65 + dt))), rel=1e-12)
    assert atm.temperature == pytest.approx([216.65 + dt, 216.65 + dt], rel=1e-12)


@pytest.mark.parametrize('dt, dp0', [(15.0, 500.0), (-30.0, -800.0)])
def test_non_standard_day_against_hydrostatic_integration(dt, dp0):
    def rhs(H, y):
        h = H * 6356766.0 / (6356766.0 - H)
        return [-G0 / (R * (fluids.ATMOSPHERE_1976(float(h)).T + dt))]
    H = np.linspace(0.0, 32000.0, 33)
    sol = solve_ivp(rhs, (0.0, 32000.0), [np.log(P0 + dp0)], t_eval=H, rtol=1e-11, atol=1e-12, max_step=250.0)
    atm = Atmosphere(geometric_height(H), DayOffsets(dt, dp0))
    np.testing.assert_allclose(atm.pressure, np.exp(sol.y[0]), rtol=1e-8)


def test_sea_level_offset_alone_scales_every_height():
    h = np.linspace(0.0, 30000.0, 31)
    ratio = Atmosphere(h, DayOffsets(0.0, 1013.25)).pressure / Atmosphere(h).pressure
    np.testing.assert_allclose(ratio, 1.01, rtol=1e-14)


def test_a_warm_day_is_a_taller_column():
    # same pressure level, higher on a warm day: the thickness scales with the temperature
    p = 20000.0
    cold, warm = (Atmosphere.from_pressure(p, DayOffsets(dt, 0.0)).geopotential for dt in (-20.0, 20.0))
    assert warm > Atmosphere.from_pressure(p).geopotential > cold


def test_day_offsets_are_validated():
    with pytest.raises(ConfigError):
        build(DayOffsets, {'delta_t_k': 100.0})
    assert build(DayOffsets, {'delta_t_k': 10, 'delta_p0_pa': -300}) == DayOffsets(10.0, -300.0)
