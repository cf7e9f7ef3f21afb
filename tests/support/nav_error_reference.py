"""Reference for the error models' tests (not a test module): the exact nonlinear strapdown
navigation equations of a true and an erroneous INS, and the time derivative of their
difference, by finite differences. Nothing here comes from alignment_core.models.

True INS (ENU, local level):  C' = C [w_ib x] - [w_in x] C,   V' = C f^b - (2 w_ie + w_en) x V + g,
                              L' = V_N / (R_M + h),  lon' = V_E / ((R_N + h) cos L),  h' = V_U,
with w_ie, w_en, R_M, R_N, g from the WGS-84 formulas at the INS's own (L, h, V). The erroneous
INS runs the same equations from C_est = exp(-[phi x]) C, V + dV, L + dlat, lon + dlon, on the
compensated sensors w_ib + eps, f^b + nabla (eps, nabla the residual biases, body axes).
Errors: phi = -log(C_est C^T), dV = V_est - V, dlat, dlon.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

A = 6378137.0
F_FLAT = 1.0 / 298.257223563
E2 = F_FLAT * (2.0 - F_FLAT)
OMEGA = 7.292115e-5


def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def expm_so3(v):
    return Rotation.from_rotvec(v).as_matrix()


def log_so3(c):
    return Rotation.from_matrix(c).as_rotvec()


def earth_terms(lat, h, v):
    """(w_ie, w_en, g vector, R_M, R_N): WGS-84, written out here independently."""
    s2 = np.sin(lat) ** 2
    den = 1.0 - E2 * s2
    r_n = A / np.sqrt(den)
    r_m = A * (1.0 - E2) / den ** 1.5
    w_ie = OMEGA * np.array([0.0, np.cos(lat), np.sin(lat)])
    w_en = np.array([-v[1] / (r_m + h), v[0] / (r_n + h), v[0] * np.tan(lat) / (r_n + h)])
    g0 = 9.7803253359 * (1.0 + 0.00193185265241 * s2) / np.sqrt(den)
    g = g0 * (1.0 - 2.0 * h / A)
    return w_ie, w_en, np.array([0.0, 0.0, -g]), r_m, r_n


@dataclass(frozen=True)
class Ins:
    c: np.ndarray       # C_b^n
    v: np.ndarray
    lat: float
    lon: float
    h: float


def rates(s: Ins, w_ib, f_b):
    """(w_in, V', L', lon', h') of INS state s driven by w_ib, f_b."""
    w_ie, w_en, g, r_m, r_n = earth_terms(s.lat, s.h, s.v)
    vdot = s.c @ f_b - np.cross(2.0 * w_ie + w_en, s.v) + g
    return w_ie + w_en, vdot, s.v[1] / (r_m + s.h), s.v[0] / ((r_n + s.h) * np.cos(s.lat)), s.v[2]


def advance(s: Ins, w_ib, f_b, tau: float) -> Ins:
    """s moved by tau along its own derivative (attitude on the rotation group)."""
    w_in, vdot, ld, lod, hd = rates(s, w_ib, f_b)
    c = expm_so3(-w_in * tau) @ s.c @ expm_so3(w_ib * tau)
    return Ins(c, s.v + tau * vdot, s.lat + tau * ld, s.lon + tau * lod, s.h + tau * hd)


@dataclass(frozen=True)
class Point:
    """A true navigation state and its true body rate / specific force."""
    ins: Ins
    w_nb: np.ndarray     # body rate w.r.t. nav, body axes
    f_b: np.ndarray      # specific force, body axes

    @property
    def w_ib(self):
        w_ie, w_en, _, _, _ = earth_terms(self.ins.lat, self.ins.h, self.ins.v)
        return self.w_nb + self.ins.c.T @ (w_ie + w_en)

    @property
    def f_n(self):
        return self.ins.c @ self.f_b


ZERO3 = np.zeros(3)


def errors(est: Ins, true: Ins) -> dict:
    return {'phi': -log_so3(est.c @ true.c.T), 'dv': est.v - true.v, 'dlat': est.lat - true.lat,
            'dlon': est.lon - true.lon}


def estimate(p: Point, phi=ZERO3, dv=ZERO3, dlat=0.0, dlon=0.0) -> Ins:
    s = p.ins
    return Ins(expm_so3(-np.asarray(phi)) @ s.c, s.v + np.asarray(dv), s.lat + dlat, s.lon + dlon, s.h)


def error_rate(p: Point, phi=ZERO3, dv=ZERO3, dlat=0.0, dlon=0.0, eps=ZERO3, nabla=ZERO3,
               tau: float = 1e-2, hold_vertical: bool = False) -> dict:
    """d/dt of the errors at the given error state (central difference over +-tau of both INS).
    hold_vertical: the erroneous INS's vertical velocity rate is the true one (an externally
    damped vertical channel: dV_U stays 0)."""
    est = estimate(p, phi, dv, dlat, dlon)
    w_est, f_est = p.w_ib + np.asarray(eps), p.f_b + np.asarray(nabla)
    out = {}
    plus, minus = [], []
    for sgn, acc in ((1.0, plus), (-1.0, minus)):
        t_true = advance(p.ins, p.w_ib, p.f_b, sgn * tau)
        t_est = advance(est, w_est, f_est, sgn * tau)
        if hold_vertical:
            t_est = replace(t_est, v=np.array([t_est.v[0], t_est.v[1], est.v[2] + (t_true.v[2] - p.ins.v[2])]))
        acc.append(errors(t_est, t_true))
    for k in plus[0]:
        out[k] = (np.asarray(plus[0][k]) - np.asarray(minus[0][k])) / (2.0 * tau)
    return out


def jacobian(rate_of_state, n: int, steps: np.ndarray) -> np.ndarray:
    """Central-difference Jacobian (n x n) of x -> rate_of_state(x) at x = 0."""
    cols = []
    for j in range(n):
        e = np.zeros(n)
        e[j] = steps[j]
        cols.append((rate_of_state(e) - rate_of_state(-e)) / (2.0 * steps[j]))
    return np.stack(cols, axis=1)


def points(speed: float = 8.0) -> list[Point]:
    """Three dissimilar true states: a rolling ship deck, an aircraft in a 2 g stroke, a
    banked turn in the southern hemisphere."""
    r = Rotation.from_euler
    return [
        Point(Ins(r('ZYX', [30.0, 2.0, -4.0], degrees=True).as_matrix(), np.array([0.6, 1.0, 0.05]) * speed / 1.17,
                  np.radians(40.0), np.radians(116.0), 15.0),
              np.array([0.02, -0.01, 0.005]), np.array([0.3, -0.5, 9.9])),
        Point(Ins(r('ZYX', [-70.0, -1.0, 3.0], degrees=True).as_matrix(), np.array([-speed, 0.3 * speed, 0.0]),
                  np.radians(30.0), np.radians(120.0), 20.0),
              np.array([0.0, 0.0, 0.0]), np.array([19.6, 0.2, 9.8])),
        Point(Ins(r('ZYX', [150.0, 5.0, 30.0], degrees=True).as_matrix(), np.array([0.5, -0.8, 0.1]) * speed,
                  np.radians(-20.0), np.radians(10.0), 500.0),
              np.array([0.01, 0.03, 0.08]), np.array([1.0, 4.9, 8.5])),
    ]


def context(p: Point, h: float = 0.01):
    """The models' Propagation context at a true point (estimate = truth)."""
    from alignment_core.estimation.models import Propagation
    w_ie, w_en, _, _, _ = earth_terms(p.ins.lat, p.ins.h, p.ins.v)
    return Propagation(c_nb=p.ins.c, f_n=p.f_n, w_ie=w_ie, w_en=w_en, v_n=p.ins.v, lat=p.ins.lat,
                       height=p.ins.h, h=h)
