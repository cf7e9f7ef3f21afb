"""Spectral ship motion: low-frequency course plus wave-frequency response through RAOs.

eta = eta_LF + eta_WF. The low-frequency part (`ShipConfig.course_keeping`) is either a
straight course at constant speed ('straight'): a rhumb line on the WGS-84 ellipsoid
(constant ENU velocity and yaw), integrated in closed form (meridian arc by Gauss-Legendre
quadrature, inverted by Newton), so its position is the exact integral of its velocity; or
the MMG manoeuvring model steered by an autopilot ('mmg', `course_keeping.ManoeuvringTrack`:
heading, speed, roll and position of the track, with exact derivatives), along which the
wave-frequency response follows `WaveFrequencyOnTrack` (below; the straight-course formulas
of the next paragraphs are its special case).

Wave frequency (no ODE): for each wave component (absolute frequency w, wave number k,
travelling towards chi in ENU, amplitude A, phase eps) the ship meets the phase
  phi(t) = w t - k . r_LF(t) + eps = w_e t + eps,   w_e = w - k U cos(beta),
with beta = psi_LF - chi the wave direction relative to the bow (clockwise), i.e. the phase
is the integral of the signed encounter frequency along the track. The six wave-frequency
DOF (surge, sway, heave in the ship's mean-heading axes; roll, pitch, yaw as ROS Euler
increments) are
  x_i(t) = sum Re{ H~_i A e^{i phi} },   H~ = H(w, beta, U) if w_e >= 0 else conj(H),
(conjugate: for w_e < 0 the elevation at the ship turns at |w_e| the other way), and their
derivatives multiply H~ by (i w_e) and (-w_e^2): exact, analytic.

Truth at the master INS point: Euler (roll, pitch, yaw) = (x4, x5, psi_LF + x6); body rate
and angular acceleration through geometry.euler.euler_rates_to_body_rate / euler_acc_to_body_acc;
ENU velocity v_LF + Rz(psi_LF) (x1', x2', x3') and its exact derivative; position on the
ellipsoid with the wave-frequency displacement added (heave as height).

Evaluation is vectorised: on a uniform time grid, chunks of C samples cost one real matrix
product [cos(w_e m dt), -sin(w_e m dt)] (C x 2M, built once) @ [Re; Im](e^{i phi(t_chunk)} W)
(2M x 18); any other times are evaluated directly. Both give the same numbers to rounding.
"""
from __future__ import annotations

from collections import OrderedDict

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.geometry import earth
from alignment_core.geometry.euler import euler_acc_to_body_acc, euler_rates_to_body_rate, heading_to_yaw
from alignment_core.rng import stage_rng
from alignment_core.samples import ShipBatch, ShipSample
from alignment_core.ship import rao, sea_state, wave_spectrum
from alignment_core.ship.config import ShipConfig
from alignment_core.ship.manoeuvring.course_keeping import ManoeuvringTrack, quintic_coefficients, quintic_values
from alignment_core.ship.phase_terms import phase_terms
from alignment_core.ship.stamped import split, stamped_batch
from alignment_core.ship.track import StraightCourse
from alignment_core.units import DEG, KNOT


class WaveFrequencyMotion:
    """Wave-frequency response of the six DOF to a set of wave components, for a ship on a
    straight course (mean yaw psi, ROS) at constant speed U."""

    CHUNK = 1024

    def __init__(self, comps: wave_spectrum.WaveComponents, rao_fn, speed: float, psi: float,
                 scale: float = 1.0, heave: bool = True) -> None:
        self.comps = comps
        self.speed = speed
        self.beta = np.mod(psi - comps.chi, 2.0 * np.pi)       # relative to the bow, clockwise
        self.omega_e = comps.omega - comps.k * speed * np.cos(self.beta)      # signed
        h = np.asarray(rao_fn(comps.omega, self.beta, speed), dtype=complex)
        h = np.where((self.omega_e < 0.0)[:, None], np.conj(h), h)
        if not heave:
            h[:, 2] = 0.0
        self.h = h
        w0 = h * (scale * comps.amp)[:, None]                    # (M, 6)
        we = self.omega_e[:, None]
        # columns: x (6), x' (6), x'' (6), elevation at the ship (1)
        self.weights = np.concatenate([w0, 1j * we * w0, -we**2 * w0,
                                       (scale * comps.amp)[:, None].astype(complex)], axis=1)
        self._basis: tuple[float, np.ndarray] | None = None

    def variance(self) -> np.ndarray:
        """Variance of each DOF (6,), sum |H A|^2 / 2."""
        return np.sum(np.abs(self.weights[:, :6]) ** 2, axis=0) / 2.0

    def moments(self, n: int) -> np.ndarray:
        """Spectral moments m_n (6,) of each DOF in encounter frequency."""
        return np.sum(np.abs(self.omega_e[:, None]) ** n * np.abs(self.weights[:, :6]) ** 2, axis=0) / 2.0

    def _uniform_dt(self, t: np.ndarray) -> float | None:
        n = len(t)
        if n < 64:
            return None
        dt = (t[-1] - t[0]) / (n - 1)
        if not dt > 0.0:
            return None
        if np.max(np.abs(t - (t[0] + dt * np.arange(n)))) > 1e-11:
            return None
        return dt

    def evaluate(self, t) -> np.ndarray:
        """(N, 19): x (6), x' (6), x'' (6) and the elevation at the ship, at times t (s)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty((len(t), self.weights.shape[1]))
        we, eps, wts = self.omega_e, self.comps.phase, self.weights
        dt = self._uniform_dt(t)
        if dt is None:
            for a in range(0, len(t), 2048):
                z = np.exp(1j * (np.outer(t[a:a + 2048], we) + eps))
                out[a:a + 2048] = (z @ wts).real
            return out
        c = self.CHUNK
        if self._basis is None or self._basis[0] != dt:
            arg = np.outer(np.arange(c) * dt, we)
            self._basis = (dt, np.ascontiguousarray(np.hstack([np.cos(arg), -np.sin(arg)])))
        q = self._basis[1]
        for a in range(0, len(t), c):
            m = min(c, len(t) - a)
            wc = np.exp(1j * (we * t[a] + eps))[:, None] * wts
            out[a:a + m] = q[:m] @ np.vstack([wc.real, wc.imag])
        return out


def _smoothstep(u, du, ddu):
    """Quintic smoothstep S(u) = 10u^3 - 15u^4 + 6u^5 of u clipped to [0, 1] (C2), and the
    first two time derivatives of S(u(t)) given u', u''."""
    inside = (u > 0.0) & (u < 1.0)
    uc = np.clip(u, 0.0, 1.0)
    s = uc**3 * (10.0 - 15.0 * uc + 6.0 * uc * uc)
    s1 = np.where(inside, 30.0 * uc**2 * (1.0 - uc) ** 2, 0.0)
    s2 = np.where(inside, 60.0 * uc * (1.0 - uc) * (1.0 - 2.0 * uc), 0.0)
    return s, s1 * du, s2 * du * du + s1 * ddu


class WaveFrequencyOnTrack:
    """Wave-frequency response of the six DOF along a manoeuvring track (course_keeping
    'mmg'). Each component's phase is phi = w t - k . r_LF(t) + eps, the exact integral of
    its encounter frequency along the track, so phi' = w - k . v_LF and phi'' = -k . a_LF.
    The RAOs are evaluated at the initial course and speed and, when the schedule orders a
    turn, also at the final ordered course and ordered speed; the response blends the two
    with a C2 smoothstep of the heading's progress through the turn (1 - S) x_a + S x_b.
    Between, the amplitudes are an interpolation (the RAO of the momentary heading is not
    recomputed per sample); the encounter periods follow the track exactly. Derivatives are
    analytic: x' and x'' include phi', phi'', S' and S''."""

    CHUNK = 256
    KNOT_S = 0.1              # knot spacing of the sampled response (s)
    BLOCK = 256               # knots per cached block
    CACHE = 4                 # blocks kept (a run read forward needs two at a time)

    def __init__(self, comps: wave_spectrum.WaveComponents, rao_fn, courses, heading_span,
                 scale: float = 1.0, heave: bool = True, track=None) -> None:
        """courses: [(speed, ROS yaw)] one or two; heading_span: (psi0, psi1) MMG headings
        (rad) over which the second set blends in (None: a single set); track: the
        ManoeuvringTrack `evaluate` follows when not given its kinematics."""
        self.comps, self.track = comps, track
        self.kx = comps.k * np.cos(comps.chi)                 # East component
        self.ky = comps.k * np.sin(comps.chi)                 # North component
        sets = []
        for speed, psi in courses:
            beta = np.mod(psi - comps.chi, 2.0 * np.pi)
            we = comps.omega - comps.k * speed * np.cos(beta)
            h = np.asarray(rao_fn(comps.omega, beta, speed), dtype=complex)
            h = np.where((we < 0.0)[:, None], np.conj(h), h)
            if not heave:
                h[:, 2] = 0.0
            sets.append(h * (scale * comps.amp)[:, None])
        self.n_sets = len(sets)
        self.span = heading_span if self.n_sets > 1 else None
        w = np.concatenate(sets + [(scale * comps.amp)[:, None].astype(complex)], axis=1)
        self.n_cols = w.shape[1]
        self._wr, self._wi = np.ascontiguousarray(w.real), np.ascontiguousarray(w.imag)
        self._k2 = np.vstack([self.kx, self.ky])              # (2, M): k . (east, north)
        self._blocks: OrderedDict[int, np.ndarray] = OrderedDict()

    def _block(self, b: int) -> np.ndarray:
        """Quintic coefficients (BLOCK, 19, 6) of the knots b*BLOCK .. (b+1)*BLOCK (cached;
        each block is computed alone, so any order of evaluation gives the same numbers)."""
        c = self._blocks.get(b)
        if c is not None:
            self._blocks.move_to_end(b)
            return c
        h = self.KNOT_S
        tk = (b * self.BLOCK + np.arange(self.BLOCK + 1)) * h
        x = self.evaluate(tk)
        c = quintic_coefficients(x[:-1, 0:6], x[:-1, 6:12], x[:-1, 12:18], x[1:, 0:6], x[1:, 6:12],
                                 x[1:, 12:18], h)
        elev = x[:, 18]
        ce = np.zeros((self.BLOCK, 1, 6))
        ce[:, 0, 0], ce[:, 0, 1] = elev[:-1], elev[1:] - elev[:-1]     # elevation: linear
        c = np.concatenate([c, ce], axis=1)
        self._blocks[b] = c
        if len(self._blocks) > self.CACHE:
            self._blocks.popitem(last=False)
        return c

    def at(self, t) -> np.ndarray:
        """(N, 19) like `evaluate`, from the quintic Hermite interpolant of the response on
        knots every KNOT_S seconds (value, rate and acceleration matched at the knots, so
        the result is C2 and its rates are exactly the derivatives of its values; the
        interpolation error is < 1e-4 of a component's amplitude up to 12 rad/s encounter
        frequency). Times t >= 0."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        h = self.KNOT_S
        j = np.maximum(np.floor(t / h).astype(np.int64), 0)
        out = np.empty((len(t), 19))
        blocks = j // self.BLOCK
        for b in np.unique(blocks):
            sel = blocks == b
            c = self._block(int(b))[j[sel] - b * self.BLOCK]             # (n, 7, 6)
            s = (t[sel] / h - j[sel])[:, None]
            v, d1, d2 = quintic_values(c, s, h, 2)
            out[sel, 0:6], out[sel, 6:12], out[sel, 12:18] = v[:, :6], d1[:, :6], d2[:, :6]
            out[sel, 18] = v[:, 6]
        return out

    def evaluate(self, t, lf: dict[str, np.ndarray] | None = None) -> np.ndarray:
        """(N, 19): x (6), x' (6), x'' (6) and the elevation at the ship, at times t along the
        low-frequency kinematics `lf` (default: the track's kinematics at t)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if lf is None:
            if self.track is None:
                raise ValueError('evaluate: no track was given, so its kinematics must be')
            lf = self.track.kinematics(t)
        n = len(t)
        e, nn = lf['east'], lf['north']
        ve, vn = lf['v_n'][:, 0], lf['v_n'][:, 1]
        ae, an = lf['a_n'][:, 0], lf['a_n'][:, 1]
        c = self.comps
        kk = self._k2
        pos = np.stack([e, nn], axis=1)
        vel = np.stack([ve, vn], axis=1)
        acc = np.stack([ae, an], axis=1)
        wr, wi = self._wr, self._wi
        val = np.empty((n, self.n_cols))
        d1 = np.empty((n, self.n_cols))
        d2 = np.empty((n, self.n_cols))
        terms = np.empty((6, min(n, self.CHUNK), len(c.omega)))
        for a in range(0, n, self.CHUNK):
            sl = slice(a, min(n, a + self.CHUNK))
            ph = np.outer(t[sl], c.omega) - pos[sl] @ kk
            ph += c.phase
            pd = c.omega - vel[sl] @ kk                      # phi'
            pdd = acc[sl] @ kk                               # -phi''
            if pd.shape != ph.shape or pdd.shape != ph.shape:    # one row of kinematics: the kernel reads all
                pd, pdd = (np.ascontiguousarray(np.broadcast_to(x, ph.shape)) for x in (pd, pdd))
            # Z = e^{i phi} = cs + i sn, i phi' Z = -spd + i cpd, G = (i phi'' - phi'^2) Z = gr + i gi
            cs, sn, spd, cpd, gr, gi = terms[:, :len(ph)]
            phase_terms(ph, pd, pdd, cs, sn, spd, cpd, gr, gi)
            val[sl] = cs @ wr - sn @ wi                      # Re{Z W}
            d1[sl] = -(spd @ wr + cpd @ wi)                  # Re{i phi' Z W}
            d2[sl] = gr @ wr - gi @ wi                       # Re{G W}
        out = np.empty((n, 19))
        out[:, 18] = val[:, -1]
        if self.n_sets == 1:
            out[:, 0:6], out[:, 6:12], out[:, 12:18] = val[:, :6], d1[:, :6], d2[:, :6]
            return out
        assert self.span is not None                    # n_sets > 1 comes with a span
        p0, p1 = self.span
        u = (lf['psi'] - p0) / (p1 - p0)
        s, s1, s2 = _smoothstep(u, lf['psi_dot'] / (p1 - p0), lf['psi_ddot'] / (p1 - p0))
        s, s1, s2 = s[:, None], s1[:, None], s2[:, None]
        xa, xb = val[:, 0:6], val[:, 6:12]
        va, vb = d1[:, 0:6], d1[:, 6:12]
        out[:, 0:6] = (1.0 - s) * xa + s * xb
        out[:, 6:12] = (1.0 - s) * va + s * vb + s1 * (xb - xa)
        out[:, 12:18] = ((1.0 - s) * d2[:, 0:6] + s * d2[:, 6:12] + 2.0 * s1 * (vb - va)
                         + s2 * (xb - xa))
        return out


class SpectralShipMotion:
    """Ship truth for `mode: spectral`: a straight course at constant speed, or the MMG
    track, plus the wave-frequency response of all six DOF to a random sea (see the module
    docstring)."""

    def __init__(self, cfg: ShipConfig, seed: int, rao_fn=None,
                 comps: wave_spectrum.WaveComponents | None = None) -> None:
        """`rao_fn` / `comps` replace the configured RAOs / the random sea (tests)."""
        self.cfg = cfg
        self.lat0, self.lon0 = cfg.lat_deg * DEG, cfg.lon_deg * DEG
        self.plane = earth.TangentPlane(self.lat0, self.lon0, 0.0)
        hd = cfg.heading_deg * DEG
        self.lf = StraightCourse(self.lat0, self.lon0, hd, cfg.speed_kn * KNOT)
        self.sea = sea_state.resolve(cfg.sea_state, cfg.hs_m, cfg.tp_s,
                                     stage_rng(seed, 'ship_sea') if cfg.sea_draw else None)
        if comps is None:
            chi0 = self.lf.yaw - cfg.wave_heading_deg * DEG      # travel direction, ENU
            comps = wave_spectrum.synthesize(
                cfg.spectrum, self.sea.hs_m, self.sea.tp_s, chi0, stage_rng(seed, 'ship_waves'),
                n_frequencies=cfg.n_frequencies, n_directions=cfg.n_directions,
                spreading=cfg.spreading, omega_min=cfg.omega_min, omega_max=cfg.omega_max,
                gamma=cfg.jonswap_gamma)
        self.comps = comps
        if rao_fn is None:
            rao_fn = rao.make(cfg.rao_source, rao.CarrierParams(roll_period_s=cfg.roll_period_s,
                                                                roll_zeta=cfg.roll_zeta))
        self.rao = rao_fn
        self.track: ManoeuvringTrack | None = None
        self.wf: WaveFrequencyOnTrack | WaveFrequencyMotion
        if cfg.course_keeping == 'mmg':
            from alignment_core.ship.track import make_track
            self.track = make_track(cfg)
            sched = self.track.sched
            courses = [(sched.speed0, heading_to_yaw(sched.heading0))]
            span = None
            if sched.turning and abs(sched.final_heading - sched.heading0) > 1e-9:
                courses.append((sched.speed(sched.turn_at), heading_to_yaw(sched.final_heading)))
                span = (sched.heading0, sched.final_heading)
            self.wf = WaveFrequencyOnTrack(comps, rao_fn, courses, span, scale=cfg.motion_scale,
                                           heave=cfg.heave, track=self.track)
        else:
            self.wf = WaveFrequencyMotion(comps, rao_fn, self.lf.speed, self.lf.yaw,
                                          scale=cfg.motion_scale, heave=cfg.heave)

    def batch(self, t) -> dict[str, np.ndarray]:
        """Truth arrays at times t (s since start): euler, euler_dot, euler_ddot (N, 3) ROS,
        p_w, q_nb, v_n, a_n, v_b, a_b, w_b, wdot_b, and the wave-frequency DOF `wf` (N, 19)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if self.track is not None:
            return self._batch_track(t)
        x = self.wf.evaluate(t)
        n = len(t)
        psi = self.lf.yaw
        e = np.empty((n, 3))
        e[:, 0], e[:, 1], e[:, 2] = x[:, 3], x[:, 4], psi + x[:, 5]
        ed, edd = x[:, 9:12], x[:, 15:18]
        cp, sp = np.cos(psi), np.sin(psi)

        def to_nav(a):                          # ship mean-heading axes -> ENU
            return np.stack([cp * a[:, 0] - sp * a[:, 1], sp * a[:, 0] + cp * a[:, 1], a[:, 2]], axis=-1)
        d_n = to_nav(x[:, 0:3])
        v_n = self.lf.v_n + to_nav(x[:, 6:9])
        a_n = to_nav(x[:, 12:15])
        lat, lon = self.lf.geodetic(t)
        r_m, r_n = earth.radii(lat)
        lat_w = lat + d_n[:, 1] / r_m
        lon_w = lon + d_n[:, 0] / (r_n * np.cos(lat))
        p_w = self.plane.from_geodetic(lat_w, lon_w, d_n[:, 2])
        rot = Rotation.from_euler('ZYX', e[:, ::-1])
        c_nb = rot.as_matrix()
        return {'t': t, 'euler': e, 'euler_dot': ed, 'euler_ddot': edd, 'p_w': p_w,
                'q_nb': rot.as_quat(), 'v_n': v_n, 'a_n': a_n,
                'v_b': np.einsum('nji,nj->ni', c_nb, v_n), 'a_b': np.einsum('nji,nj->ni', c_nb, a_n),
                'w_b': euler_rates_to_body_rate(e, ed), 'wdot_b': euler_acc_to_body_acc(e, ed, edd),
                'lat': lat_w, 'lon': lon_w, 'wf': x}

    def _batch_track(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """`batch` for course_keeping 'mmg': the wave-frequency DOF in the axes of the track's
        heading psi(t) (ROS yaw), so the ENU displacement d = R(psi) x has the velocity
        R x' + psi' R J x and the acceleration R x'' + 2 psi' R J x' + psi'' R J x - psi'^2 R x
        (J: +90 deg rotation); roll of the track added to the wave roll."""
        track, wf = self.track, self.wf
        assert track is not None and isinstance(wf, WaveFrequencyOnTrack)     # course_keeping 'mmg'
        lf = track.kinematics(t)
        x = wf.at(t)
        n = len(t)
        psi = heading_to_yaw(lf['psi'])
        pd, pdd = -lf['psi_dot'], -lf['psi_ddot']
        e = np.empty((n, 3))
        e[:, 0], e[:, 1], e[:, 2] = x[:, 3] + lf['phi'], x[:, 4], psi + x[:, 5]
        ed = x[:, 9:12].copy()
        edd = x[:, 15:18].copy()
        ed[:, 0] += lf['phi_dot']
        edd[:, 0] += lf['phi_ddot']
        ed[:, 2] += pd
        edd[:, 2] += pdd
        cp, sp = np.cos(psi), np.sin(psi)

        def rot(a):                                # R(psi) a, horizontal components
            return cp * a[:, 0] - sp * a[:, 1], sp * a[:, 0] + cp * a[:, 1]

        def rot_j(a):                              # R(psi) J a
            return -sp * a[:, 0] - cp * a[:, 1], cp * a[:, 0] - sp * a[:, 1]
        d0, d1, d2 = x[:, 0:3], x[:, 6:9], x[:, 12:15]
        de, dn = rot(d0)
        v_n = lf['v_n'].copy()
        a_n = lf['a_n'].copy()
        r1, rj0 = rot(d1), rot_j(d0)
        r2, rj1 = rot(d2), rot_j(d1)
        for i in range(2):
            v_n[:, i] += r1[i] + pd * rj0[i]
            a_n[:, i] += r2[i] + 2.0 * pd * rj1[i] + pdd * rj0[i] - pd * pd * (de, dn)[i]
        v_n[:, 2] += d1[:, 2]
        a_n[:, 2] += d2[:, 2]
        lat, lon = lf['lat'], lf['lon']
        r_m, r_n = earth.radii(lat)
        lat_w = lat + dn / r_m
        lon_w = lon + de / (r_n * np.cos(lat))
        p_w = self.plane.from_geodetic(lat_w, lon_w, d0[:, 2])
        rot_nb = Rotation.from_euler('ZYX', e[:, ::-1])
        c_nb = rot_nb.as_matrix()
        return {'t': t, 'euler': e, 'euler_dot': ed, 'euler_ddot': edd, 'p_w': p_w,
                'q_nb': rot_nb.as_quat(), 'v_n': v_n, 'a_n': a_n,
                'v_b': np.einsum('nji,nj->ni', c_nb, v_n), 'a_b': np.einsum('nji,nj->ni', c_nb, a_n),
                'w_b': euler_rates_to_body_rate(e, ed), 'wdot_b': euler_acc_to_body_acc(e, ed, edd),
                'lat': lat_w, 'lon': lon_w, 'wf': x, 'lf': lf}

    def sample_batch(self, t: np.ndarray, t0_ns: int, dt_ns: int, k0: int = 0) -> ShipBatch:
        """Ship samples k0 .. k0+len(t)-1 at times t (s since start), stamps t0_ns + k*dt_ns."""
        b = self.batch(t)
        return stamped_batch(t0_ns, dt_ns, k0, b['p_w'], b['q_nb'], b['v_b'], b['w_b'], b['a_b'], b['wdot_b'])

    def samples(self, t: np.ndarray, t0_ns: int, dt_ns: int, k0: int = 0) -> list[ShipSample]:
        """`sample_batch` as samples."""
        return split(self.sample_batch(t, t0_ns, dt_ns, k0))
