"""The port pressure model's limits, written out independently:
- eps = -1.25 is incompressible potential flow over a sphere, (p - p_inf) / qc = 1 - 9/4 sin^2 sigma
  (and qc -> q as M -> 0, so Cp -> 1 - 9/4 sin^2 sigma);
- eps = 0 is modified Newtonian flow, Cp = (p - p_inf) / q = Cp_max cos^2 sigma with
  Cp_max = (p_t2 - p_inf) / q from the Rayleigh pitot formula (1.8237 at Mach 7);
- the centre port at alpha = beta = 0 reads the total pressure p_inf (1 + 0.2 M^2)^3.5;
- on the vertical meridian the incidence is |alpha - lambda| (bottom) and alpha + lambda (top);
- the analytic Jacobian against central differences; the flow-angle convention (FLU).
"""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.air_data.flow_angles import air_angles, air_direction, air_velocity
from alignment_core.air_data.port_layout import EpsilonCalibration, PortGeometry
from alignment_core.air_data.ports import PortModel, port_pressures
from alignment_core.validation import ConfigError, build

DEG = np.pi / 180.0
LAM = 30.0 * DEG


def incidence(alpha, beta, cone, clock):
    """sigma from the textbook FRD formulas: v = (cos a cos b, sin b, sin a cos b),
    n = (cos l, sin l sin p, sin l cos p)."""
    v = np.array([np.cos(alpha) * np.cos(beta), np.sin(beta), np.sin(alpha) * np.cos(beta)])
    n = np.array([np.cos(cone), np.sin(cone) * np.sin(clock), np.sin(cone) * np.cos(clock)])
    return np.arccos(np.clip(n @ v, -1.0, 1.0))


def grid():
    a, b = np.meshgrid(np.linspace(-50, 50, 11) * DEG, np.linspace(-20, 20, 5) * DEG)
    return a.ravel(), b.ravel()


def test_flow_angle_convention_flu():
    v = air_velocity(100.0, 10 * DEG, 5 * DEG)
    # alpha > 0: the air comes from below (v_a has a downward, -z component in FLU);
    # beta > 0: from the right (v_a points to the right, -y)
    assert v[2] < 0.0 and v[1] < 0.0 and v[0] > 0.0
    speed, a, b = air_angles(v)
    assert (speed, a, b) == pytest.approx((100.0, 10 * DEG, 5 * DEG), rel=1e-14)
    np.testing.assert_allclose(np.linalg.norm(air_direction(*grid()), axis=-1), 1.0, rtol=1e-15)


def test_geometry_normals():
    n = PortGeometry().normals
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(n[0], [1, 0, 0], atol=1e-15)
    s, c = np.sin(LAM), np.cos(LAM)
    # bottom, right, top, left
    np.testing.assert_allclose(n[1:], [[c, 0, -s], [c, -s, 0], [c, 0, s], [c, s, 0]], atol=1e-15)


def test_incidence_against_the_frd_formula():
    model = PortModel()
    a, b = grid()
    cos_sigma = model.cos_incidence(a, b)
    g = model.geometry
    for i in range(5):
        expect = [incidence(x, y, g.cone_deg[i] * DEG, g.clock_deg[i] * DEG) for x, y in zip(a, b)]
        np.testing.assert_allclose(np.arccos(cos_sigma[:, i]), expect, atol=1e-7)
    # vertical meridian at beta = 0: sigma = |alpha - lambda| below, alpha + lambda on top
    alpha = np.linspace(-50, 50, 21) * DEG
    c = model.cos_incidence(alpha, 0.0)
    np.testing.assert_allclose(c[:, 1], np.cos(alpha - LAM), atol=1e-15)
    np.testing.assert_allclose(c[:, 3], np.cos(alpha + LAM), atol=1e-15)
    np.testing.assert_allclose(c[:, 0], np.cos(alpha), atol=1e-15)


def test_sphere_limit():
    model = PortModel(epsilon=EpsilonCalibration.constant(-1.25))
    a, b = grid()
    for mach in (0.01, 0.5):
        p_inf = 7e4
        p = model.pressures(a, b, mach, p_inf)
        qc = p_inf * ((1 + 0.2 * mach**2) ** 3.5 - 1)
        sin2 = np.sin(np.arccos(model.cos_incidence(a, b))) ** 2
        np.testing.assert_allclose((p - p_inf) / qc, 1.0 - 2.25 * sin2, atol=1e-12)
    # incompressible: Cp over q = 0.7 p M^2 -> 1 - 9/4 sin^2 sigma (qc / q = 1 + M^2/4 + ...)
    p = model.pressures(a, b, 0.01, 7e4)
    np.testing.assert_allclose((p - 7e4) / (0.7 * 7e4 * 0.01**2), 1.0 - 2.25 * sin2, atol=1e-4)


def test_newtonian_limit_at_mach_7():
    model = PortModel(epsilon=EpsilonCalibration.constant(0.0))
    a, b = grid()
    p_inf, m = 5529.3, 7.0
    cp_max = (166.92158 * m**7 / (7 * m**2 - 1) ** 2.5 - 1.0) / (0.7 * m**2)
    assert cp_max == pytest.approx(1.8237, abs=1e-4)
    cp = (model.pressures(a, b, m, p_inf) - p_inf) / (0.7 * p_inf * m**2)
    np.testing.assert_allclose(cp, cp_max * model.cos_incidence(a, b) ** 2, rtol=1e-7)


@pytest.mark.parametrize('mach', [0.3, 0.9, 3.0])
def test_stagnation_port_reads_total_pressure(mach):
    p_inf = 26436.0
    p = PortModel().pressures(0.0, 0.0, mach, p_inf)
    total = p_inf * (1 + 0.2 * mach**2) ** 3.5 if mach < 1 else p_inf * 166.92158 * mach**7 / (7 * mach**2 - 1) ** 2.5
    assert p[0] == pytest.approx(total, rel=5e-8)
    assert np.all(p[1:] < p[0])


def test_lee_side_is_refused():
    model = PortModel()
    assert np.all(model.in_view(*grid()))                   # alpha +-50, beta +-20: all windward
    assert not model.in_view(70 * DEG, 0.0)                 # top port at sigma = 100 deg
    with pytest.raises(ValueError):
        model.pressures(70 * DEG, 0.0, 0.5, 5e4)
    assert model.pressures(70 * DEG, 0.0, 0.5, 5e4, strict=False).shape == (5,)


def test_port_pressures_formula():
    c = np.array([[1.0, 0.5, 0.0]])
    np.testing.assert_allclose(port_pressures(1000.0, 5e4, c, 0.2),
                               [[51000.0, 5e4 + 1000 * (0.25 + 0.2 * 0.75), 50200.0]])


def test_jacobian_against_central_differences():
    model = PortModel()                         # the default eps table: the eps slope enters dp/dM
    rng = np.random.default_rng(3)
    for _ in range(20):
        x = np.array([rng.uniform(-50, 50) * DEG, rng.uniform(-20, 20) * DEG, rng.uniform(0.1, 7),
                      rng.uniform(5e3, 9e4)])
        steps = np.array([1e-6, 1e-6, 1e-6, 1e-2])
        fd = np.stack([(model.pressures(*(x + s * e)) - model.pressures(*(x - s * e))) / (2 * s)
                       for s, e in zip(steps, np.eye(4))], axis=-1)
        np.testing.assert_allclose(model.jacobian(*x), fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
    alpha = np.linspace(-0.5, 0.5, 7)
    assert model.jacobian(alpha, 0.0, 0.5, 5e4).shape == (7, 5, 4)
    np.testing.assert_allclose(model.jacobian(alpha, 0.0, 0.5, 5e4)[3], model.jacobian(alpha[3], 0.0, 0.5, 5e4))


def test_epsilon_table():
    table = EpsilonCalibration()
    np.testing.assert_allclose(table(np.array(table.mach)), table.eps, atol=1e-15)
    assert float(table(50.0)) == pytest.approx(table.eps[-1], abs=1e-15)
    assert float(table(-1.0)) == pytest.approx(table.eps[0], abs=1e-15)
    assert float(table.slope(50.0)) == 0.0
    m = np.linspace(0.05, 3.9, 40)
    np.testing.assert_allclose(table.slope(m), (table(m + 1e-6) - table(m - 1e-6)) / 2e-6, atol=1e-6)
    with pytest.raises(ConfigError):
        build(EpsilonCalibration, {'mach': [0.0, 2.0, 1.0], 'eps': [0.0, 0.0, 0.0]})
    with pytest.raises(ConfigError):
        build(EpsilonCalibration, {'mach': [0.0, 1.0], 'eps': [0.0, 1.0]})
    with pytest.raises(ConfigError):
        build(PortGeometry, {'cone_deg': [0.0, 95.0, 30.0], 'clock_deg': [0.0, 0.0, 90.0]})
