"""The aircraft on the deck and through the catapult stroke, and its ideal IMU output.

The aircraft's IMU sits at lever arm r (ship FLU axes, from the master INS) with a mounting
misalignment mu (rotation vector, aircraft FLU axes: C_a^s = exp([mu x])). During the stroke
it moves along the catapult track (the aircraft's x axis) with r(t) = r0 + s(t) u; after the
stroke it flies free at its release velocity and attitude (constant in the nav frame).

Ideal increments are integrals over each sample interval of omega_ib^a and f^a evaluated by
3-point Gauss-Legendre quadrature on the ship state, which is interpolated inside the
interval by cubic Hermite polynomials from the samples' values and derivatives (rate with
angular acceleration, velocity with acceleration). Catapult events fall on the sample grid
(validated), so no interval straddles a discontinuity.

At a point P on the rigid ship: v_P = v + C(w x r + r'), a_P = a + C(w' x r + w x (w x r)
+ 2 w x r' + r''); omega_ib^a = C_s^a w + C_n^a (omega_ie + omega_en);
f^a = C_n^a (a_P + (2 omega_ie + omega_en) x v_P - g).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from . import earth
from .attitude import ARCMIN, G0
from .config import require
from .samples import AircraftTruth, ShipSample

GL_NODES = np.array([0.5 - 0.5 * np.sqrt(0.6), 0.5, 0.5 + 0.5 * np.sqrt(0.6)])
GL_WEIGHTS = np.array([5.0, 8.0, 5.0]) / 18.0


@dataclass(frozen=True)
class CatapultConfig:
    """Catapult stroke: constant acceleration along the aircraft axis (seed 000: 2 g, 3 s)."""
    enabled: bool = True
    launch_time_s: float = 60.0
    stroke_s: float = 3.0
    accel_g: float = 2.0

    def validate(self) -> None:
        require(self.launch_time_s >= 0.0, f"launch_time_s must be >= 0, got {self.launch_time_s}")
        require(0.0 < self.stroke_s <= 10.0, f"stroke_s must be in (0, 10], got {self.stroke_s}")
        require(0.0 < self.accel_g <= 8.0, f"accel_g must be in (0, 8], got {self.accel_g}")


@dataclass(frozen=True)
class AircraftConfig:
    """Deck spot and mounting. Default misalignment is seed 000's (10', 15', -30') in its
    right-forward-up axes, i.e. (15', -10', -30') in FLU (x fwd/roll, y left, z up/yaw)."""
    lever_arm_m: tuple[float, float, float] = (40.0, -10.0, 15.0)
    misalignment_arcmin: tuple[float, float, float] = (15.0, -10.0, -30.0)
    catapult: CatapultConfig = field(default_factory=CatapultConfig)

    def validate(self) -> None:
        r = np.asarray(self.lever_arm_m)
        require(np.hypot(r[0], r[1]) <= 200.0 and abs(r[2]) <= 50.0,
                f"lever_arm_m out of range (|horizontal| <= 200 m, |z| <= 50 m): {self.lever_arm_m}")
        require(np.all(np.abs(self.misalignment_arcmin) <= 600.0),
                f"misalignment_arcmin must be within +-600' per axis: {self.misalignment_arcmin}")


class AircraftKinematics:
    """Relative motion on the deck, release state and ideal IMU increments."""

    def __init__(self, cfg: AircraftConfig, plane: earth.TangentPlane, rate_hz: float) -> None:
        self.cfg = cfg
        self.plane = plane
        self.r0 = np.asarray(cfg.lever_arm_m, dtype=float)
        self.mu = np.asarray(cfg.misalignment_arcmin, dtype=float) * ARCMIN
        self.c_sa = Rotation.from_rotvec(self.mu).as_matrix()          # C_a^s
        self.track = self.c_sa[:, 0]                                     # aircraft x in ship axes
        cat = cfg.catapult
        self.launch = cat.launch_time_s if cat.enabled else np.inf
        self.release = cat.launch_time_s + cat.stroke_s if cat.enabled else np.inf
        self.acc = cat.accel_g * G0
        for name, t in (('launch_time_s', self.launch), ('launch + stroke', self.release)):
            if np.isfinite(t):
                require(abs(t * rate_hz - round(t * rate_hz)) < 1e-6,
                        f"aircraft.catapult.{name} = {t} s must fall on the {rate_hz} Hz sample grid")
        self.release_state: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def relative(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """r, r', r'' (N, 3) in ship axes at times tau (s since scenario start), on deck."""
        tau = np.asarray(tau, dtype=float)
        s_t = np.clip(tau - self.launch, 0.0, self.release - self.launch)
        moving = ((tau > self.launch) & (tau <= self.release)).astype(float)
        s = 0.5 * self.acc * s_t**2
        sd = self.acc * s_t
        sdd = self.acc * moving
        r = self.r0 + s[:, None] * self.track
        return r, sd[:, None] * self.track, sdd[:, None] * self.track

    def _on_deck(self, c_nb, w, wd, v_n, a_n, p_w, tau):
        """Aircraft nav quantities on the deck (vectorised over leading dim N)."""
        r, rd, rdd = self.relative(tau)
        wxr = np.cross(w, r)
        v_p = v_n + np.einsum('nij,nj->ni', c_nb, wxr + rd)
        a_rel = np.cross(wd, r) + np.cross(w, wxr) + 2.0 * np.cross(w, rd) + rdd
        a_p = a_n + np.einsum('nij,nj->ni', c_nb, a_rel)
        p_p = p_w + np.einsum('nij,nj->ni', c_nb, r)
        c_na = c_nb @ self.c_sa                                          # C_a^n
        w_na = w @ self.c_sa                                             # C_s^a w (row form)
        return c_na, w_na, v_p, a_p, p_p

    def _free(self, tau):
        c_rel, v_rel, p_rel = self.release_state
        n = len(tau)
        c_na = np.broadcast_to(c_rel, (n, 3, 3))
        v_p = np.tile(v_rel, (n, 1))
        p_p = p_rel + np.outer(tau - self.release, v_rel)
        return c_na, np.zeros((n, 3)), v_p, np.zeros((n, 3)), p_p

    def _imu(self, c_na, w_na, v_p, a_p, p_p):
        lat, _, h = self.plane.to_geodetic(p_p)
        w_ie = earth.omega_ie_n(lat)
        w_en = earth.omega_en_n(lat, h, v_p)
        w_ib = w_na + np.einsum('nji,nj->ni', c_na, w_ie + w_en)
        f_n = a_p + np.cross(2.0 * w_ie + w_en, v_p) - earth.gravity_n(lat, h)
        return w_ib, np.einsum('nji,nj->ni', c_na, f_n)

    def truth(self, s: ShipSample, tau: float) -> AircraftTruth:
        """Aircraft truth at a ship sample (tau = its time since scenario start)."""
        on_deck = tau <= self.release
        c_nb = Rotation.from_quat(s.q_nb).as_matrix()
        if on_deck:
            c_na, w_na, v_p, _, p_p = self._on_deck(
                c_nb[None], s.w_b[None], s.wdot_b[None], (c_nb @ s.v_b)[None],
                (c_nb @ s.a_b)[None], s.p_w[None], np.array([tau]))
            if tau == self.release:
                self.release_state = (c_na[0].copy(), v_p[0].copy(), p_p[0].copy())
        else:
            c_na, w_na, v_p, _, p_p = self._free(np.array([tau]))
        c_na = c_na[0]
        return AircraftTruth(t_ns=s.t_ns, p_w=p_p[0], q_nb=Rotation.from_matrix(c_na).as_quat(),
                             v_b=c_na.T @ v_p[0], w_b=w_na[0], misalignment=self.mu.copy(),
                             on_deck=bool(on_deck))

    def increments(self, s0: ShipSample, s1: ShipSample, tau0: float, tau1: float
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Ideal (delta_theta, delta_v), each (3,), over (tau0, tau1] between two ship samples."""
        h = tau1 - tau0
        u = GL_NODES
        tau = tau0 + u * h
        if tau0 >= self.release:
            if self.release_state is None:
                raise RuntimeError("free flight before the release state was seen")
            w_ib, f = self._imu(*self._free(tau))
        else:
            c0 = Rotation.from_quat(s0.q_nb).as_matrix()
            c1 = Rotation.from_quat(s1.q_nb).as_matrix()
            # cubic Hermite basis, its derivative and its integral from 0 to u
            h00, h10, h01, h11 = 2*u**3 - 3*u**2 + 1, u**3 - 2*u**2 + u, -2*u**3 + 3*u**2, u**3 - u**2
            d00, d10, d01, d11 = 6*u**2 - 6*u, 3*u**2 - 4*u + 1, -6*u**2 + 6*u, 3*u**2 - 2*u
            i00, i10 = u**4/2 - u**3 + u, u**4/4 - 2*u**3/3 + u**2/2
            i01, i11 = -u**4/2 + u**3, u**4/4 - u**3/3
            w = np.outer(h00, s0.w_b) + np.outer(h10 * h, s0.wdot_b) + np.outer(h01, s1.w_b) \
                + np.outer(h11 * h, s1.wdot_b)
            wd = (np.outer(d00, s0.w_b) + np.outer(d10 * h, s0.wdot_b) + np.outer(d01, s1.w_b)
                  + np.outer(d11 * h, s1.wdot_b)) / h
            th = h * (np.outer(i00, s0.w_b) + np.outer(i10 * h, s0.wdot_b) + np.outer(i01, s1.w_b)
                      + np.outer(i11 * h, s1.wdot_b))
            c_nb = c0 @ Rotation.from_rotvec(th).as_matrix()
            v0, v1 = c0 @ s0.v_b, c1 @ s1.v_b
            a0, a1 = c0 @ s0.a_b, c1 @ s1.a_b
            v_n = np.outer(h00, v0) + np.outer(h10 * h, a0) + np.outer(h01, v1) + np.outer(h11 * h, a1)
            a_n = (np.outer(d00, v0) + np.outer(d10 * h, a0) + np.outer(d01, v1)
                   + np.outer(d11 * h, a1)) / h
            p_w = np.outer(1.0 - u, s0.p_w) + np.outer(u, s1.p_w)
            w_ib, f = self._imu(*self._on_deck(c_nb, w, wd, v_n, a_n, p_w, tau))
        return h * (GL_WEIGHTS @ w_ib), h * (GL_WEIGHTS @ f)
