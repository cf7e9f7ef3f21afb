"""The aircraft on the deck, through the catapult stroke and in flight, and its ideal IMU output.

The aircraft's IMU sits at lever arm r (ship FLU axes, from the master INS), its nominal axes
turned by the heading on deck psi_d (`heading_on_deck_deg`, from the bow, clockwise: the
angled deck's waist catapults are about -9 deg) and then by a mounting misalignment mu
(rotation vector, aircraft FLU axes): C_a^s = Rz(-psi_d) exp([mu x]). The catapult track is the
aircraft's x axis, u = C_a^s e_x; on it the aircraft moves r(t) = r0 + s(t) u (catapult.py:
hold-back creep, then the stroke's acceleration profile). After the release it either keeps
its release velocity and attitude (constant in the nav frame; `aircraft.flight.segments` '')
or flies a segment list (aircraft/flight.py: climbs, turns, with Earth rate and transport rate).
With `aircraft.flight.start: airborne` (catapult disabled) there is no deck phase: the flight
starts at the scenario start (flight.airborne_start) and every sample is in flight.

Ideal increments are integrals over each sample interval of omega_ib^a and f^a evaluated by
3-point Gauss-Legendre quadrature on the ship state, which is interpolated inside the
interval by cubic Hermite polynomials from the samples' values and derivatives (rate with
angular acceleration, velocity with acceleration). Catapult events fall on the sample grid
(validated), so no interval straddles a discontinuity.

At a point P on the rigid ship: v_P = v + C(w x r + r'), a_P = a + C(w' x r + w x (w x r)
+ 2 w x r' + r''); omega_ib^a = C_s^a w + C_n^a (omega_ie + omega_en);
f^a = C_n^a (a_P + (2 omega_ie + omega_en) x v_P - g).

Optional effects (all off by default, leaving the default output bit-identical):
- aircraft.vibration (vibration.py): nose-gear vibration from the launch, on the
  accelerometers only or as real motion; its share of the increments is integrated in
  closed form (the quadrature sees r, r' of the vibration but not its r'').
- aircraft.flexure (deck_flexure.py): C_a^s(t) = exp([mu x]) exp([theta(t) x]), body rate
  + J_r(theta) theta'; the aircraft truth attitude carries it (the true relative attitude),
  while the reported misalignment stays the mounting mu. The catapult track stays the
  mounted aircraft x axis C_a^s(mu) e_x (the deck rail does not follow the flexure).
- aircraft.gear (landing_gear.py, gear_response.py, gear_on_deck.py): the airframe on its landing gear, driven by
  the deck's motion at the rigidly mounted CG, gusts and the hold-back pull; the IMU point moves
  by C_d^s d_imu(t) (C_d^s: the heading on deck) and the airframe turns by theta_g (airframe
  axes), which enters as a relative rotation exp(-mu) theta_g added to the flexure's theta
  (C_a^s = exp([mu x]) exp([(theta_f + exp(-mu) theta_g) x]) after the heading; the sum of the
  two small rotation vectors stands for their composition). The reported misalignment stays mu.
- output='sample' (imu.output): point values of omega_ib^a and f^a at the end of each interval
  (times the interval, so the error model's increment / interval gives the point value).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.aircraft.aircraft_config import AircraftConfig
from alignment_core.aircraft.catapult import CatapultMotion, check_catapult_grid
from alignment_core.aircraft.deck_flexure import FlexureProcess
from alignment_core.aircraft.flight import FlightPath, airborne_start
from alignment_core.aircraft.gear_on_deck import GearOnDeck
from alignment_core.aircraft.interval_hermite import hermite_basis, hermite_nodes
from alignment_core.aircraft.vibration import Vibration
from alignment_core.geometry import earth
from alignment_core.geometry.rotation_stacks import products, right_jacobians, rotated
from alignment_core.geometry.rotations import (
    cross,
    quat_mul_batch,
    quat_to_dcm_batch,
    relative_rotvec_batch,
    rotvec_to_dcm_batch,
    rows_matmul,
)
from alignment_core.rng import stage_rng
from alignment_core.samples import AircraftTruth, ShipBatch, ShipSample
from alignment_core.units import ARCMIN, DEG

__all__ = ['AircraftKinematics']

GL_NODES = np.array([0.5 - 0.5 * np.sqrt(0.6), 0.5, 0.5 + 0.5 * np.sqrt(0.6)])
GL_WEIGHTS = np.array([5.0, 8.0, 5.0]) / 18.0
HERMITE = hermite_basis(GL_NODES)


class AircraftKinematics:
    """Relative motion on the deck, release state and ideal IMU increments. With flight
    segments, `path` (flight.FlightPath, set when the release sample is seen, or at once for
    an airborne start) gives the flight truth at any time after the release: `path.state(tau)`."""

    def __init__(self, cfg: AircraftConfig, plane: earth.TangentPlane, rate_hz: float,
                 output: str = 'increment', seed: int = 0) -> None:
        self.cfg = cfg
        self.output = output
        self.plane = plane
        self.r0 = np.asarray(cfg.lever_arm_m, dtype=float)
        self.mu = np.asarray(cfg.misalignment_arcmin, dtype=float) * ARCMIN
        if cfg.misalignment_random_arcmin > 0.0:
            self.mu = self.mu + stage_rng(seed, 'mounting').standard_normal(3) * cfg.misalignment_random_arcmin * ARCMIN
        self.q_sa = Rotation.from_rotvec(self.mu).as_quat()
        if cfg.heading_on_deck_deg != 0.0:
            half = -0.5 * cfg.heading_on_deck_deg * DEG                  # ROS yaw is anticlockwise
            self.q_sa = quat_mul_batch(np.array([0.0, 0.0, np.sin(half), np.cos(half)]), self.q_sa)
        self.c_sa = quat_to_dcm_batch(self.q_sa)                         # C_a^s
        self.track = self.c_sa[:, 0]                                     # aircraft x in ship axes
        cat = cfg.catapult
        self.enabled = cat.enabled
        if cat.enabled:
            check_catapult_grid(cat, rate_hz)
            self.catapult = CatapultMotion(cat, rate_hz)
            self.launch, self.release = self.catapult.launch, self.catapult.release
        else:
            self.launch = self.release = np.inf
        self.release_state: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.flying = bool(cfg.flight.parsed())                          # segments given
        self.path: FlightPath | None = None                              # set at the release
        if cfg.flight.start == 'airborne':                               # in flight from tau = 0
            self.release = -np.inf
            self.path = FlightPath(cfg.flight, plane, 0.0, *airborne_start(cfg.flight, plane))
        vib = cfg.vibration
        self.vib = Vibration(vib, self.launch) if (vib.enabled and cat.enabled) else None
        self.vib_motion = self.vib is not None and vib.mode == 'motion'
        self.flex = FlexureProcess(cfg.flexure, seed, rate_hz) if cfg.flexure.enabled else None
        self.gear: GearOnDeck | None = None
        if cfg.gear.enabled:
            holdback = None
            if cat.enabled and cat.holdback_s > 0.0:
                holdback = (self.catapult.holdback_start, self.launch)
            self.gear = GearOnDeck(cfg.gear, cfg.heading_on_deck_deg, self.mu, self.r0, plane, seed, rate_hz,
                                   holdback, self._imu)
        self.has_rot = self.flex is not None or self.gear is not None

    def _flex_at(self, tau):
        """(theta, theta') of the relative rotation (flexure and gear, aircraft axes) at the sample
        instants tau, or None without either."""
        if self.gear is None:
            return None if self.flex is None else self.flex.at(self.flex.index(tau))
        th, thd = self.gear.rotation(tau)
        if self.flex is None:
            return th, thd
        tf, tfd = self.flex.at(self.flex.index(tau))
        return tf + th, tfd + thd

    def _c_sa(self, flex):
        if flex is None:
            return self.c_sa
        th = flex[0]
        return rotated(self.c_sa[None], th.reshape(1, -1, 3)).reshape(th.shape + (3,))

    def relative(self, tau: np.ndarray, vib_acc: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """r, r', r'' (..., 3) in ship axes at times tau (...) (s since scenario start), on deck.
        With motion-mode vibration, its displacement and velocity are included, and its
        acceleration unless vib_acc is False (the increments add that part exactly); with the
        gear, the IMU point's motion on it."""
        tau = np.asarray(tau, dtype=float)
        if not self.enabled:
            z = np.zeros(tau.shape + (3,))
            r, rd, rdd = self.r0 + z, z, z
        else:
            s, sd, sdd = self.catapult.along(tau)
            r = self.r0 + s[..., None] * self.track
            rd, rdd = sd[..., None] * self.track, sdd[..., None] * self.track
        if self.gear is not None:
            d, v, a = self.gear.displacement(tau)
            r, rd, rdd = r + d, rd + v, rdd + a
        vib = self.vib
        if not self.vib_motion or vib is None:        # (vib_motion implies a vibration model)
            return r, rd, rdd
        rd = rd + rows_matmul(vib.vel(tau), self.c_sa.T)
        if vib_acc:
            rdd = rdd + rows_matmul(vib.acc(tau), self.c_sa.T)
        return r + rows_matmul(vib.pos(tau), self.c_sa.T), rd, rdd

    def _on_deck(self, c_nb, w, wd, v_n, a_n, p_w, tau, flex=None, vib_acc=True, c_lw=None):
        """Aircraft nav quantities on the deck; leading dims (...) of tau, vectors (..., 3);
        flex = (theta, theta') (..., 3) of the deck flexure or None; c_lw: the local-to-world
        rotations at p_w if already made."""
        r, rd, rdd = self.relative(tau, vib_acc)
        wxr = cross(w, r)
        v_p = v_n + np.einsum('...ij,...j->...i', c_nb, wxr + rd)
        a_rel = cross(wd, r) + cross(w, wxr) + 2.0 * cross(w, rd) + rdd
        a_p = a_n + np.einsum('...ij,...j->...i', c_nb, a_rel)
        # C r is in the local-level frame at the ship; p_w in the world tangent plane
        if c_lw is None:
            c_lw = self.plane.c_local_to_world(p_w)
        p_p = p_w + np.einsum('...ij,...j->...i', c_lw, np.einsum('...ij,...j->...i', c_nb, r))
        if flex is None:
            c_na = c_nb @ self.c_sa                                      # C_a^n
            w_na = rows_matmul(w, self.c_sa)                             # C_s^a w (row form)
        else:
            c_sa = self._c_sa(flex)
            c_na = products(c_nb, c_sa)
            w_na = (np.einsum('...ji,...j->...i', c_sa, w)
                    + np.einsum('...ij,...j->...i', right_jacobians(flex[0]), flex[1]))
        return c_na, w_na, v_p, a_p, p_p

    def _check_released(self) -> None:
        if self.release_state is None:
            raise RuntimeError('free flight before the release state was seen')

    def _free(self, tau):
        c_rel, v_rel, p_rel = self.release_state
        tau = np.asarray(tau, dtype=float)
        c_na = np.broadcast_to(c_rel, tau.shape + (3, 3))
        v_p = np.broadcast_to(v_rel, tau.shape + (3,))
        p_p = p_rel + (tau - self.release)[..., None] * self.release_v_world
        return c_na, np.zeros(tau.shape + (3,)), v_p, np.zeros(tau.shape + (3,)), p_p

    def _imu(self, c_na, w_na, v_p, a_p, p_p):
        lat, _, h = self.plane.to_geodetic(p_p)
        return self._imu_at(c_na, w_na, v_p, a_p, lat, h)

    def _imu_at(self, c_na, w_na, v_p, a_p, lat, h):
        """omega_ib^a and f^a from the nav-frame motion at geodetic latitude and height."""
        w_ie = earth.omega_ie_n(lat)
        w_en = earth.omega_en_n(lat, h, v_p)
        w_ib = w_na + np.einsum('...ji,...j->...i', c_na, w_ie + w_en)
        f_n = a_p + cross(2.0 * w_ie + w_en, v_p) - earth.gravity_n(lat, h)
        return w_ib, np.einsum('...ji,...j->...i', c_na, f_n)

    def truth_batch(self, sb: ShipBatch, tau: np.ndarray) -> dict[str, np.ndarray]:
        """Aircraft truth at K ship samples: p_w, q_nb, v_b, w_b (K, ...) and on_deck (K,).
        Records the release state when the release instant is among the samples."""
        tau = np.asarray(tau, dtype=float)
        c_nb = quat_to_dcm_batch(sb.q_nb)
        on = tau <= self.release
        c_na = np.empty((len(tau), 3, 3))
        w_na = np.zeros((len(tau), 3))
        v_p = np.empty((len(tau), 3))
        p_p = np.empty((len(tau), 3))
        flex = None
        if np.any(on):
            c_on, p_on = c_nb[on], sb.p_w[on]
            c_lw = self.plane.c_local_to_world(p_on)
            if self.gear is not None:
                self.gear.feed(sb.slice(on), tau[on], c_on, c_lw)
            v_n = np.einsum('kij,kj->ki', c_on, sb.v_b[on])
            a_n = np.einsum('kij,kj->ki', c_on, sb.a_b[on])
            flex = self._flex_at(tau[on])
            c_na[on], w_na[on], v_p[on], _, p_p[on] = self._on_deck(
                c_on, sb.w_b[on], sb.wdot_b[on], v_n, a_n, p_on, tau[on], flex, c_lw=c_lw)
        if not self.has_rot:
            q_sa = self.q_sa
        else:
            q_sa = np.broadcast_to(self.q_sa, (len(tau), 4)).copy()
            if flex is not None:
                q_sa[on] = quat_mul_batch(self.q_sa, Rotation.from_rotvec(flex[0]).as_quat())
        q = quat_mul_batch(sb.q_nb, q_sa)
        if np.any(on):
            rel = np.flatnonzero(tau == self.release)
            if len(rel):
                k = rel[0]
                self.release_state = (c_na[k].copy(), v_p[k].copy(), p_p[k].copy())
                self.release_quat = q[k].copy() if self.has_rot else quat_mul_batch(sb.q_nb[k], self.q_sa)
                self.release_v_world = self.plane.c_local_to_world(p_p[k]) @ v_p[k]
                if self.flying and self.path is None:
                    self.path = FlightPath(self.cfg.flight, self.plane, tau[k], v_p[k], p_p[k],
                                           self.release_quat, w_na[k])
        if np.any(~on):
            if self.path is None:
                self._check_released()
                c_na[~on], w_na[~on], v_p[~on], _, p_p[~on] = self._free(tau[~on])
                q[~on] = self.release_quat
            else:
                st = self.path.state(tau[~on])
                c_na[~on], w_na[~on], v_p[~on], p_p[~on], q[~on] = st.c_na, st.w_na, st.v_n, st.p_w, st.q
        return {'p_w': p_p, 'q_nb': q, 'v_b': np.einsum('kji,kj->ki', c_na, v_p), 'w_b': w_na,
                'on_deck': on}

    def truth(self, s: ShipSample, tau: float) -> AircraftTruth:
        """Aircraft truth at one ship sample (tau = its time since scenario start)."""
        d = self.truth_batch(ShipBatch.of([s]), np.array([tau]))
        return AircraftTruth(t_ns=s.t_ns, p_w=d['p_w'][0], q_nb=d['q_nb'][0], v_b=d['v_b'][0], w_b=d['w_b'][0],
                             misalignment=relative_rotvec_batch(s.q_nb, d['q_nb'][0]), on_deck=bool(d['on_deck'][0]))

    def increments_batch(self, s0: ShipBatch, s1: ShipBatch, tau0: np.ndarray, tau1: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
        """Ideal (delta_theta, delta_v), each (K, 3), over (tau0, tau1] for K intervals
        (output 'sample': the point values at tau1 times the interval)."""
        tau0 = np.asarray(tau0, dtype=float)
        h = np.asarray(tau1, dtype=float) - tau0                         # (K,)
        if self.output == 'sample':
            return self._points(s1, tau0, np.asarray(tau1, dtype=float), h)
        u = GL_NODES                                                     # (J,)
        tau = tau0[:, None] + u[None, :] * h[:, None]                    # (K, J)
        w_ib = np.empty(tau.shape + (3,))
        f = np.empty(tau.shape + (3,))
        free = tau0 >= self.release
        if np.any(free):
            if self.path is None:
                self._check_released()
                w_ib[free], f[free] = self._imu(*self._free(tau[free]))
            else:
                w_ib[free], f[free] = 0.0, 0.0                           # replaced below
        deck = ~free
        if np.any(deck):
            hk = np.ascontiguousarray(h[deck])
            a = s0.slice(deck) if not np.all(deck) else s0
            b = s1.slice(deck) if not np.all(deck) else s1
            c0, c1 = quat_to_dcm_batch(a.q_nb), quat_to_dcm_batch(b.q_nb)
            w, wd, th = hermite_nodes(a.w_b, a.wdot_b, b.w_b, b.wdot_b, hk, HERMITE)
            c_nb = rotated(c0, th)
            v0 = np.einsum('kij,kj->ki', c0, a.v_b)
            v1 = np.einsum('kij,kj->ki', c1, b.v_b)
            a0 = np.einsum('kij,kj->ki', c0, a.a_b)
            a1 = np.einsum('kij,kj->ki', c1, b.a_b)
            v_n, a_n = hermite_nodes(v0, a0, v1, a1, hk, HERMITE[:2])
            uu = u[None, :, None]
            p_w = (1.0 - uu) * a.p_w[:, None] + uu * b.p_w[:, None]
            flex = None
            if self.gear is not None:
                self.gear.feed(a, tau0[deck])
                self.gear.feed(b, tau0[deck] + h[deck])
            if self.has_rot:
                (t0, d0), (t1, d1) = self._flex_at(tau0[deck]), self._flex_at(tau0[deck] + h[deck])
                flex = tuple(hermite_nodes(t0, d0, t1, d1, hk, HERMITE[:2]))
            w_ib[deck], f[deck] = self._imu(*self._on_deck(c_nb, w, wd, v_n, a_n, p_w, tau[deck],
                                                           flex, vib_acc=not self.vib_motion))
        dth = h[:, None] * np.einsum('kjc,j->kc', w_ib, GL_WEIGHTS)
        dv = h[:, None] * np.einsum('kjc,j->kc', f, GL_WEIGHTS)
        if self.path is not None and np.any(free):
            dth[free], dv[free] = self._flight_increments(tau0[free], tau0[free] + h[free])
        if self.vib is not None:
            dv = dv + self._vib_dv(tau0, tau0 + h, deck)
        return dth, dv

    def _flight_state_imu(self, tau) -> tuple[np.ndarray, np.ndarray]:
        assert self.path is not None                    # called only for an aircraft that flies
        st = self.path.state(tau)
        return self._imu_at(st.c_na, st.w_na, st.v_n, st.a_n, st.lat, st.h)

    def _flight_increments(self, tau0: np.ndarray, tau1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Increments over flight intervals (K,): 3-point Gauss-Legendre on each piece between
        the flight's breakpoints (segment and transition boundaries), summed per interval."""
        assert self.path is not None
        bp = self.path.breakpoints
        lo, hi = np.searchsorted(bp, tau0, side='right'), np.searchsorted(bp, tau1, side='left')
        starts, ends, owners = [tau0], [tau1], [np.arange(len(tau0))]
        split = np.flatnonzero(hi > lo)
        if len(split):
            starts, ends, owners = [tau0.copy()], [tau1.copy()], [np.arange(len(tau0))]
            for k in split:
                cuts = np.concatenate([[tau0[k]], bp[lo[k]:hi[k]], [tau1[k]]])
                ends[0][k] = cuts[1]
                starts.append(cuts[1:-1])
                ends.append(cuts[2:])
                owners.append(np.full(len(cuts) - 2, k))
        a, b, owner = np.concatenate(starts), np.concatenate(ends), np.concatenate(owners)
        hp = b - a
        nodes = a[:, None] + GL_NODES[None, :] * hp[:, None]
        w_ib, f = self._flight_state_imu(nodes)
        dth_p = hp[:, None] * np.einsum('kjc,j->kc', w_ib, GL_WEIGHTS)
        dv_p = hp[:, None] * np.einsum('kjc,j->kc', f, GL_WEIGHTS)
        if not len(split):
            return dth_p, dv_p
        dth, dv = np.zeros((len(tau0), 3)), np.zeros((len(tau0), 3))
        np.add.at(dth, owner, dth_p)
        np.add.at(dv, owner, dv_p)
        return dth, dv

    def _vib_dv(self, tau0, tau1, deck):
        """Exact vibration share of delta_v (K, 3), aircraft axes. Motion mode: only on the
        deck, rotated by C_s^a(t) C_a^s(mu) = exp(-theta) at mid-interval under flexure."""
        dv = self.vib.dv(tau0, tau1)
        if not self.vib_motion:
            return dv
        dv = np.where(deck[:, None], dv, 0.0)
        if self.has_rot and np.any(deck):
            (t0, _), (t1, _) = self._flex_at(tau0[deck]), self._flex_at(tau1[deck])
            c = rotvec_to_dcm_batch(0.5 * (t0 + t1))
            dv[deck] = np.einsum('kji,kj->ki', c, dv[deck])
        return dv

    def _points(self, s1: ShipBatch, tau0, tau1, h):
        """Point values of omega_ib^a and f^a at tau1 (K, 3), times h."""
        w_ib = np.empty((len(h), 3))
        f = np.empty((len(h), 3))
        free = tau0 >= self.release
        if np.any(free):
            if self.path is None:
                self._check_released()
                w_ib[free], f[free] = self._imu(*self._free(tau1[free]))
            else:
                w_ib[free], f[free] = self._flight_state_imu(tau1[free])
        deck = ~free
        if np.any(deck):
            b = s1.slice(deck) if not np.all(deck) else s1
            c1 = quat_to_dcm_batch(b.q_nb)
            v_n = np.einsum('kij,kj->ki', c1, b.v_b)
            a_n = np.einsum('kij,kj->ki', c1, b.a_b)
            w_ib[deck], f[deck] = self._imu(*self._on_deck(
                c1, b.w_b, b.wdot_b, v_n, a_n, b.p_w, tau1[deck], self._flex_at(tau1[deck])))
        if self.vib is not None and not self.vib_motion:
            f = f + self.vib.acc(tau1)
        return w_ib * h[:, None], f * h[:, None]

    def increments(self, s0: ShipSample, s1: ShipSample, tau0: float, tau1: float
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Ideal (delta_theta, delta_v), each (3,), over (tau0, tau1] between two ship samples."""
        dth, dv = self.increments_batch(ShipBatch.of([s0]), ShipBatch.of([s1]),
                                        np.array([tau0]), np.array([tau1]))
        return dth[0], dv[0]
