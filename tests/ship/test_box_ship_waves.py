"""Seed 002's box-ship wave forces (eq 7): limits, Froude-Krylov integrals over the box, and
the surge they drive in the MMG model."""
from __future__ import annotations

import math

import numpy as np
import pytest

from alignment_core.ship.manoeuvring import box_ship_waves
from alignment_core.ship.manoeuvring.box_ship_waves import BoxShipWaves
from alignment_core.ship.manoeuvring.mmg import CARRIER, MmgModel, rk4_step

RHO, G = 1025.0, box_ship_waves.G
L, B, D = 310.0, 40.5, 11.3
A = 2.5


def test_head_seas_give_no_sway_roll_or_yaw_and_beam_seas_no_surge_pitch_or_yaw():
    """x = 0 (head seas): sin x = 0 and sin(kB sin x/2) = 0, so Y = K = N = 0 exactly;
    x = 90 deg: sin(kL cos x/2) -> 0 and P(q) ~ q^3/12 -> 0, so X = M = N = 0."""
    theta = np.linspace(0.0, 2.0 * np.pi, 7)
    for k in (0.005, 0.03, 0.2):
        f = box_ship_waves.forces(A, k, 0.0, theta, L, B, D)
        assert np.all(f['Y'] == 0.0) and np.all(f['K'] == 0.0) and np.all(f['N'] == 0.0)
        assert np.max(np.abs(f['X'])) > 1e5
        g = box_ship_waves.forces(A, k, np.pi / 2, theta, L, B, D)
        scale = np.max(np.abs(g['Y']))
        assert scale > 1e5
        for key in ('X', 'M', 'N'):
            assert np.max(np.abs(g[key])) < 1e-9 * scale * L


def test_long_wave_heave_force_limit():
    """k -> 0: Z = rho g a k B d L cos(theta) (every sinc and e^{-kd} -> 1), to O(k)."""
    theta = np.array([0.3, 2.0])
    k = 1e-7
    f = box_ship_waves.forces(A, k, 0.7, theta, L, B, D)
    np.testing.assert_allclose(f['Z'], RHO * G * A * k * B * D * L * np.cos(theta), rtol=1e-5)


def _froude_krylov(a, k, x, theta, n=48):
    """Surge and sway force and the side plating's yaw moment of the undisturbed pressure
    p = rho g a e^{kz} cos(k (xi dx + eta dy) - theta), (dx, dy) = (-cos x, sin x), on the
    box (outward normals), by Gauss-Legendre quadrature on every face."""
    u, w = np.polynomial.legendre.leggauss(n)
    xi, wx = 0.5 * L * u, 0.5 * L * w
    eta, wy = 0.5 * B * u, 0.5 * B * w
    z, wz = 0.5 * D * (u - 1.0), 0.5 * D * w
    dx, dy = -math.cos(x), math.sin(x)

    def p(xx, yy, zz):
        return RHO * G * a * np.exp(k * zz) * np.cos(k * (xx * dx + yy * dy) - theta)
    ez = wz[:, None]
    # ends: xi = -L/2 (normal -x) and +L/2 (normal +x)
    fx = np.sum(ez * wy[None, :] * (p(-L / 2, eta[None, :], z[:, None]) - p(L / 2, eta[None, :], z[:, None])))
    side = p(xi[None, :], -B / 2, z[:, None]) - p(xi[None, :], B / 2, z[:, None])
    fy = np.sum(ez * wx[None, :] * side)
    n_side = np.sum(ez * wx[None, :] * xi[None, :] * side)
    return fx, fy, n_side


@pytest.mark.parametrize('x_deg', [20.0, 60.0, 110.0, 160.0])
@pytest.mark.parametrize('k', [0.01, 0.04])
def test_surge_and_sway_are_froude_krylov_with_the_keel_pressure(x_deg, k):
    """Against the Froude-Krylov integrals: X/X_FK = Y/Y_FK = k d e^{-kd} / (1 - e^{-kd})
    (eq 7 takes the pressure at the keel over the whole draft, d e^{-kd}, for the depth
    integral (1 - e^{-kd})/k), and N = N_FK(sides) / (k B) with the same factor."""
    x = math.radians(x_deg)
    ratio = k * D * math.exp(-k * D) / (1.0 - math.exp(-k * D))
    for theta in (0.4, 1.9):
        f = box_ship_waves.forces(A, k, x, theta, L, B, D)
        fx, fy, n_side = _froude_krylov(A, k, x, theta)
        assert f['X'] == pytest.approx(ratio * fx, rel=1e-9)
        assert f['Y'] == pytest.approx(ratio * fy, rel=1e-9)
        assert f['N'] == pytest.approx(ratio * n_side / (k * B), rel=1e-9)


def test_scalar_forces_equal_the_vector_formulas():
    waves = BoxShipWaves(A, 0.55, 1.1, 0.3, L, B, D, 8.35)
    for t, north, east, psi in [(10.0, 100.0, -50.0, 0.2), (3.0, 5.0, 1.0, 2.7), (7.0, -3.0, 2.0, 4.0)]:
        theta = waves.omega * t - waves.kc * north - waves.ks * east + waves.eps
        f = box_ship_waves.forces(A, waves.k, math.pi - (waves.chi - psi), theta, L, B, D)
        np.testing.assert_allclose(waves.forces(t, north, east, psi),
                                   [f['X'], f['Y'], f['N'], -8.35 * f['Y']], rtol=1e-12, atol=1e-6)


def test_head_sea_surge_of_the_mmg_ship():
    """In head seas eq 7 gives only a surge force X0 sin(theta), theta' = w_e = w + k U; the
    ship's surge velocity then oscillates with amplitude X0 / ((m + m_x) w_e) (a free mass:
    the resistance and thrust slopes damp it by a fraction ~1e-3 at this frequency), about
    its mean speed. Least-squares amplitude at w_e over the last 300 s within 1 %."""
    model = MmgModel(CARRIER)
    u0 = 10.0
    n = model.equilibrium_revs(u0)
    omega = 0.55
    waves = BoxShipWaves(A, omega, math.pi, 0.0, CARRIER.lpp, CARRIER.beam, CARRIER.draft, CARRIER.z_h)
    we = omega + waves.k * u0
    x0 = box_ship_waves.forces(A, waves.k, 0.0, math.pi / 2, CARRIER.lpp, CARRIER.beam, CARRIER.draft)['X']
    h = 0.1
    y = [0.0, 0.0, 0.0, u0, 0.0, 0.0, 0.0, 0.0]
    ts, us = [], []
    for j in range(6000):
        y, _ = rk4_step(lambda t, s: model.rhs(s, 0.0, n, waves.forces(t, s[0], s[1], s[2])), j * h, y, h)
        ts.append((j + 1) * h)
        us.append(y[3])
    t, u = np.array(ts[3000:]), np.array(us[3000:])
    basis = np.stack([np.cos(we * t), np.sin(we * t), np.ones_like(t), t - t.mean()], axis=1)
    coef, *_ = np.linalg.lstsq(basis, u, rcond=None)
    assert math.hypot(coef[0], coef[1]) == pytest.approx(abs(x0) / ((model.m + model.mx) * we), rel=0.01)
