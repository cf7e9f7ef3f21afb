"""Air data from one frame of port pressures (the FADS solve), its covariance, and the
Cramer-Rao bound of any unbiased solve.

1. Angles by triples. For the ports of one meridian plane (signed in-plane angles theta_i from
   the nose axis), p_i = A + B cos(2 gamma - 2 theta_i) with gamma the flow's in-plane angle and
   B = qc (1 - eps) r^2 / 2 > 0 (r^2 the in-plane share of the flow direction): linear in
   (A, X = B cos 2 gamma, Y = B sin 2 gamma), so three ports give gamma = atan2(Y, X) / 2 over
   (-90, 90] deg without any branch and without knowing qc, p_inf or eps. The vertical meridian
   (bottom theta = +lambda, centre 0, top -lambda) gives alpha; the horizontal one (right
   +lambda, centre, left -lambda) gives beta' = atan2(sin beta, cos alpha cos beta), hence
   beta = atan(tan beta' cos alpha).
   `alpha_branch='paper'` reproduces seed 004's form instead: alpha = arctan(Y / X) / 2 in
   (-45, 45) deg, moved by +-90 deg when its sign disagrees with TAO24 = p2 - p4 (bottom minus
   top, ports 1 and 3 here). Y is that same difference, so the two forms agree wherever X != 0.
2. (qc, p_inf) by linear least squares over all ports, the paper's pseudo-inverse. Given the
   angles, p_i = u cos^2 sigma_i + w with u = qc (1 - eps), w = qc eps + p_inf: the fit
   [u, w] = pinv([cos^2 sigma, 1]) p needs no eps, and the eps(M) of the table then follows from
   one equation in M, qc/p_inf = r(M) with qc = u / (1 - eps(M)), p_inf = w - qc eps(M), solved
   by bisection on [0, MACH_MAX] (`epsilon_iteration='root'`, the default). The paper iterates
   instead (`'fixed_point'`): eps_k = eps(M_k), refit with the regressors
   cos^2 + eps_k sin^2, M_(k+1) from the new qc/p_inf, starting from Newtonian eps_0 = 0.
   Both have the same fixed point. With the loop gain
       kappa(M) = eps'(M) dM/d eps = eps'(M) r (1 + r) / ((1 - eps) r'(M))    (`epsilon_loop_gain`)
   the iteration contracts where |kappa| < 1, and the M equation has a single root where
   kappa < 1 (its slope in M is p_inf (1 - eps) r'(M) (1 - kappa)): the ports measure u and w
   only, M comes from the table, and a table that slopes too much leaves M undetermined.
   dM/d eps grows like M r(M) (~220 at Mach 7), so eps must be flat at hypersonic speed (the
   Newtonian limit is Mach-independent); the default table has kappa <= 0.33.
3. Optionally (`gauss_newton=True`) Gauss-Newton over all ports in (alpha, beta, M, p_inf) from
   that start: the maximum-likelihood solve, which reaches the Cramer-Rao bound; the triples
   alone use each meridian's three ports for its angle.

Covariance of the chosen solve: J Sigma J^T with J = d(alpha, beta, M, p_inf)/dp by central
differences of the solve itself. Cramer-Rao bound: (H^T Sigma^-1 H)^-1, H = dp/d(alpha, beta,
M, p_inf) of the port model at the true air data.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from alignment_core.air_data.pitot import (
    MACH_MAX,
    impact_pressure_ratio,
    impact_pressure_ratio_slope,
    mach_from_impact_ratio,
)
from alignment_core.air_data.ports import PortModel

STATE = ('alpha', 'beta', 'mach', 'p_inf')      # order of the solution vector and its covariance


@dataclass(frozen=True)
class FadsSolution:
    """Air data of a frame (arrays of the frames' shape; angles in rad, pressures in Pa)."""
    alpha: np.ndarray
    beta: np.ndarray
    mach: np.ndarray
    qc: np.ndarray
    p_inf: np.ndarray
    converged: np.ndarray          # the M equation (or iteration) converged and every port is windward

    def vector(self) -> np.ndarray:
        """(..., 4): alpha, beta, M, p_inf (see STATE)."""
        return np.stack([self.alpha, self.beta, self.mach, self.p_inf], axis=-1)


def _meridian(model: PortModel, vertical: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(port indices (3,), their signed in-plane angles (3,), inverse of [1, cos 2t, sin 2t])."""
    g = model.geometry
    lam, phi = np.deg2rad(g.cone_deg), np.deg2rad(g.clock_deg)
    centre = [i for i in range(g.count) if g.cone_deg[i] == 0.0]
    wanted = (0.0, 180.0) if vertical else (90.0, 270.0)
    side = [i for i in range(g.count) if g.cone_deg[i] > 0.0 and g.clock_deg[i] % 360.0 in wanted]
    if len(centre) != 1 or len(side) != 2:
        raise ValueError("the triples need one centre port and two ports on each meridian "
                         f"(clock 0/180 and 90/270 deg); geometry {g}")
    idx = np.array(centre + side)
    theta = lam[idx] * (np.cos(phi[idx]) if vertical else np.sin(phi[idx]))
    theta[0] = 0.0
    design = np.stack([np.ones(3), np.cos(2.0 * theta), np.sin(2.0 * theta)], axis=-1)
    return idx, theta, np.linalg.inv(design)


class FadsSolver:
    """Solve frames of port pressures (..., n) for air data (see the module docstring);
    `port_cov` (n, n) weights the Gauss-Newton pass (default: equal, independent ports)."""

    def __init__(self, model: PortModel, alpha_branch: Literal['atan2', 'paper'] = 'atan2',
                 epsilon_iteration: Literal['root', 'fixed_point'] = 'root', gauss_newton: bool = False,
                 port_cov: np.ndarray | None = None, max_iterations: int = 100) -> None:
        self.model = model
        self.alpha_branch = alpha_branch
        self.epsilon_iteration = epsilon_iteration
        self.gauss_newton = gauss_newton
        n = model.geometry.count
        self.weight = np.eye(n) if port_cov is None else np.linalg.inv(np.asarray(port_cov, dtype=float))
        self.max_iterations = max_iterations
        self._vertical = _meridian(model, vertical=True)
        self._horizontal = _meridian(model, vertical=False)

    # --- 1. angles ---------------------------------------------------------------------
    def angles(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(alpha, beta) in rad from the two meridian triples."""
        idx, theta, inv = self._vertical
        _, x, y = np.moveaxis(p[..., idx] @ inv.T, -1, 0)
        if self.alpha_branch == 'atan2':
            alpha = 0.5 * np.arctan2(y, x)
        else:
            with np.errstate(divide='ignore', invalid='ignore'):
                alpha = 0.5 * np.arctan(y / x)
            bottom, top = idx[1:][np.argmax(theta[1:])], idx[1:][np.argmin(theta[1:])]
            tao = p[..., bottom] - p[..., top]
            alpha = np.where((tao > 0.0) & (alpha < 0.0), alpha + 0.5 * np.pi,
                             np.where((tao < 0.0) & (alpha > 0.0), alpha - 0.5 * np.pi, alpha))
        idx, _, inv = self._horizontal
        _, x, y = np.moveaxis(p[..., idx] @ inv.T, -1, 0)
        beta_plane = 0.5 * np.arctan2(y, x)
        return alpha, np.arctan(np.tan(beta_plane) * np.cos(alpha))

    # --- 2. impact and static pressure ------------------------------------------------
    def _root(self, p: np.ndarray, c2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        design = np.stack([c2, np.ones_like(c2)], axis=-1)                      # (..., n, 2)
        u, w = np.moveaxis((np.linalg.pinv(design) @ p[..., None])[..., 0], -1, 0)
        eps_of = self.model.epsilon

        def f(m: np.ndarray) -> np.ndarray:
            e = eps_of(m)
            return impact_pressure_ratio(m) * ((1.0 - e) * w - u * e) - u

        lo, hi = np.zeros_like(u), np.full_like(u, MACH_MAX)
        ok = (f(lo) < 0.0) & (f(hi) > 0.0)
        for _ in range(64):                      # bisection to below 1e-15 of MACH_MAX
            mid = 0.5 * (lo + hi)
            up = f(mid) > 0.0
            hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
        mach = np.where(ok, 0.5 * (lo + hi), np.nan)
        e = eps_of(mach)
        qc = u / (1.0 - e)
        return mach, qc, w - qc * e

    def _fixed_point(self, p: np.ndarray, c2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        r_max = float(impact_pressure_ratio(MACH_MAX)) * (1.0 - 1e-12)
        mach = np.zeros(p.shape[:-1])
        done = np.zeros(p.shape[:-1], dtype=bool)
        for k in range(self.max_iterations):
            e = self.model.epsilon(mach)[..., None] if k else np.zeros_like(c2[..., :1])    # Newtonian start
            design = np.stack([c2 + e * (1.0 - c2), np.ones_like(c2)], axis=-1)
            qc, p_inf = np.moveaxis((np.linalg.pinv(design) @ p[..., None])[..., 0], -1, 0)
            new = mach_from_impact_ratio(np.clip(qc / p_inf, 0.0, r_max))
            done = (np.abs(new - mach) < 1e-13) & (qc > 0.0) & (p_inf > 0.0)
            mach = new
            if np.all(done):
                break
        return mach, qc, p_inf, done

    # --- 3. Gauss-Newton ----------------------------------------------------------------
    def _gauss_newton(self, p: np.ndarray, state: np.ndarray) -> np.ndarray:
        for _ in range(20):
            a, b, m, s = np.moveaxis(state, -1, 0)
            jac = self.model.jacobian(a, b, m, s)                                    # (..., n, 4)
            resid = p - self.model.pressures(a, b, m, s, strict=False)
            jtw = np.swapaxes(jac, -1, -2) @ self.weight
            step = np.linalg.solve(jtw @ jac, (jtw @ resid[..., None]))[..., 0]
            state = state + step
            if np.all(np.abs(step[..., :3]) < 1e-13) and np.all(np.abs(step[..., 3]) < 1e-9):
                break
        return state

    def solve(self, pressures: np.ndarray) -> FadsSolution:
        p = np.asarray(pressures, dtype=float)
        alpha, beta = self.angles(p)
        c2 = self.model.cos_incidence(alpha, beta) ** 2
        if self.epsilon_iteration == 'root':
            mach, qc, p_inf = self._root(p, c2)
            converged = np.isfinite(mach)
        else:
            mach, qc, p_inf, converged = self._fixed_point(p, c2)
        if self.gauss_newton:
            alpha, beta, mach, p_inf = np.moveaxis(
                self._gauss_newton(p, np.stack([alpha, beta, mach, p_inf], axis=-1)), -1, 0)
            qc = impact_pressure_ratio(mach) * p_inf
        converged = converged & self.model.in_view(alpha, beta)
        return FadsSolution(alpha, beta, mach, qc, p_inf, converged)

    def jacobian(self, pressures: np.ndarray, step_pa: float | None = None) -> np.ndarray:
        """d(alpha, beta, M, p_inf)/dp of this solve: (..., 4, n), central differences with a
        step of 1e-6 of the largest port pressure unless given."""
        p = np.asarray(pressures, dtype=float)
        n = p.shape[-1]
        h = (1e-6 * np.max(np.abs(p), axis=-1) if step_pa is None else np.full(p.shape[:-1], step_pa))
        steps = h[..., None, None] * np.eye(n)                                   # (..., n, n)
        both = self.solve(np.concatenate([p[..., None, :] + steps, p[..., None, :] - steps], axis=-2)).vector()
        diff = (both[..., :n, :] - both[..., n:, :]) / (2.0 * h[..., None, None])   # (..., n, 4)
        return np.swapaxes(diff, -1, -2)

    def covariance(self, pressures: np.ndarray, port_cov: np.ndarray) -> np.ndarray:
        """J Sigma J^T (..., 4, 4) of this solve at `pressures` for port covariance Sigma (n, n)."""
        jac = self.jacobian(pressures)
        return jac @ np.asarray(port_cov, dtype=float) @ np.swapaxes(jac, -1, -2)


def epsilon_loop_gain(model: PortModel, mach: np.ndarray | float) -> np.ndarray:
    """kappa(M) = eps'(M) r (1 + r) / ((1 - eps) r'(M)) of the table (item 2 of the module
    docstring): M is determined by the ports, and the paper's iteration converges, while kappa < 1."""
    m = np.asarray(mach, dtype=float)
    r, e = impact_pressure_ratio(m), model.epsilon(m)
    return model.epsilon.slope(m) * r * (1.0 + r) / ((1.0 - e) * impact_pressure_ratio_slope(m))


def cramer_rao_bound(model: PortModel, alpha: np.ndarray | float, beta: np.ndarray | float,
                     mach: np.ndarray | float, p_inf: np.ndarray | float, port_cov: np.ndarray) -> np.ndarray:
    """(H^T Sigma^-1 H)^-1 (..., 4, 4) in (alpha, beta, M, p_inf): the smallest covariance of any
    unbiased solve of one frame with port noise covariance Sigma (n, n)."""
    jac = model.jacobian(alpha, beta, mach, p_inf)
    info = np.swapaxes(jac, -1, -2) @ np.linalg.inv(np.asarray(port_cov, dtype=float)) @ jac
    return np.linalg.inv(info)
