"""The flight: the aircraft flies a list of segments (level, climb, turn) from its catapult
release state, or from an airborne start at the scenario start, in the local-level ENU frame
with Earth rotation and transport rate (the IMU quantities follow from this truth exactly as on
the deck; see aircraft/kinematics.py). Ground speeds up to 2500 m/s (Mach 7 at 20 km: 2066).

Kinematics. Ground velocity v = (V_h cos chi, V_h sin chi, v_U): horizontal speed V_h,
vertical speed v_U and track chi (ROS yaw: from East, counter-clockwise). Each segment sets
targets; over its transition time T every quantity q of (V_h, v_U, chi', alpha, beta) goes
from its value at the segment start to the target as q0 + (q1 - q0) S(x), x = (t - t_i) / T,
with the quintic smoothstep S(x) = 10x^3 - 15x^4 + 6x^5, so q, q' and q'' are continuous:
specific force and body rates have no steps after the release. chi and the height h are closed-form integrals.

Attitude. C_a^n = C_v^n Rz(beta) Ry(-alpha) exp([delta x]), C_v^n = Rz(chi) Ry(-gamma) Rx(mu):
velocity axes of the ground velocity (the path does not know the wind) with the flight-path
angle gamma = atan2(v_U, V_h) and the bank mu for a coordinated flight (with beta = 0 the ball
centred: no lateral specific force with the Earth taken flat and non-rotating),
  tan mu = -V_h chi' / (V gamma' + g cos gamma),
which in a steady level turn is the textbook tan(bank) = V omega / g; mu stays within
(-90, 90] deg: a pushover needing less than zero g (V gamma' < -g cos gamma, reached by a
level-off at hypersonic speed) is flown upright at negative load, not rolled inverted.
Angle of attack alpha and sideslip beta (`alpha_deg`, `beta_deg`): v in body axes is
V (cos a cos b, -sin b, -sin a cos b) (air_data/flow_angles.py); body rate
  w_na = Ry(alpha) Rz(-beta) w_v + (sin(alpha) beta', -alpha', cos(alpha) beta')
with w_v the velocity axes' rate. delta blends the deck attitude at the release into
the flight attitude over settle_s by a quintic Hermite (delta(0) and its rate chosen so the
attitude and the body rate are continuous at the release; delta, delta', delta'' = 0 at the
end). The Coriolis and transport terms (|2 omega_ie x v| ~ 0.01 m/s^2 at 60 m/s) are in the
specific force but not in the bank: a real pilot's ball would show them too.
g in the bank formula is normal gravity at the release latitude and the current height.

Turns. A turn segment gives either `bank_deg` or `turn_rate_dps` (positive = to the right,
heading increasing, ROS roll positive); the other follows from tan(bank) = V omega / g with V
the segment's speed and g at the segment's start height (30 deg at 60 m/s: 5.4 deg/s; 10 deg/s
at 60 m/s needs 46.9 deg). Climbs give one of `climb_rate_mps`, `flight_path_deg` or
`pitch_deg` (= flight-path angle + the segment's alpha, wings level; exact with beta = 0).
`speed_mps` changes the ground speed (0 / absent: keep it). The last segment may have
duration 0 (open: to the end of the run); after the last segment the aircraft keeps its
final targets. Every segment may give
`alpha_deg` (|alpha| <= 60) and `beta_deg` (|beta| <= 30), absent = keep the previous value;
the flight starts at FlightConfig.alpha_deg and beta 0. With neither key anywhere the air
angles are constant and the attitude is computed as before they existed (same floats).

Position. lat' = v_N / (R_M + h), lon' = v_E / ((R_N + h) cos lat): RK4 on a 0.05 s grid
(extended in 100 s chunks as needed, so a sample-by-sample caller gets the same numbers as a
batch caller), cubic Hermite between grid points; h in closed form. The grid's errors scale
with the derivatives of the velocity, not with the speed (well below a millimetre at 2066 m/s).

Airborne start (`start: airborne`, no catapult): the flight begins at the scenario start in
level flight at start_speed_mps along start_track_deg, start_height_m above the tangent plane's
origin latitude and longitude, already in the flight attitude (no settle blend: delta = 0).

Segment syntax (one string, so it is one ROS parameter): segments separated by ';' or new
lines, each `kind key=value ...`, e.g.
  "climb duration_s=50 climb_rate_mps=5 speed_mps=60; level duration_s=50;
   turn duration_s=300 bank_deg=30; level"
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from alignment_core.aircraft.flight_config import FlightConfig, FlightSegment
from alignment_core.geometry import earth
from alignment_core.geometry.rotations import (
    axis_quat_batch,
    quat_conj,
    quat_mul,
    quat_mul_batch,
    quat_to_dcm_batch,
    quat_to_rotvec,
    right_jacobian,
    rotvec_to_dcm_batch,
    rotvec_to_quat_batch,
)
from alignment_core.units import DEG
from alignment_core.validation import ConfigError

GRID_S = 0.05                  # position integration step
CHUNK_STEPS = 2000             # grid steps added at a time (100 s)


def gravity_and_height_rate(lat: float, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normal gravity g(lat, h) (earth.gravity) and its height derivative dg/dh, m/s^2 and 1/s^2."""
    s2 = math.sin(lat) ** 2
    g0 = earth.G_EQUATOR * (1.0 + earth.K_SOMIGLIANA * s2) / math.sqrt(1.0 - earth.E2 * s2)
    dgdh = g0 * (-2.0 / earth.A * (1.0 + earth.F + earth.M_RATIO - 2.0 * earth.F * s2) + 6.0 / earth.A**2 * h)
    return earth.gravity(lat, h), dgdh


def _smooth(x):
    """S, S', S'' and int_0^x S of the quintic smoothstep (x clipped to [0, 1])."""
    return (x**3 * (10.0 - 15.0 * x + 6.0 * x * x), 30.0 * x * x * (1.0 - x) ** 2,
            60.0 * x * (1.0 - x) * (1.0 - 2.0 * x), x**4 * (2.5 - 3.0 * x + x * x))


def airborne_start(cfg: FlightConfig, plane: earth.TangentPlane) -> tuple[np.ndarray, np.ndarray]:
    """ENU velocity (3,) and world position (3,) of an airborne start: level at start_speed_mps
    along start_track_deg, start_height_m above the plane's origin latitude and longitude."""
    lat, lon, _ = plane.to_geodetic(np.zeros(3))
    chi = cfg.start_track_deg * DEG
    v = cfg.start_speed_mps * np.array([math.cos(chi), math.sin(chi), 0.0])
    return v, plane.from_geodetic(lat, lon, cfg.start_height_m)


@dataclass
class FlightState:
    """The aircraft's flight truth at times t (leading dims): attitude q (x, y, z, w) and C_a^n,
    body rate w.r.t. the nav frame w_na (aircraft axes), ENU ground velocity v_n and its nav-frame
    derivative a_n, body-axis velocity v_b, geodetic lat, lon (rad), h (m), world position p_w,
    the bank angle mu (rad, right wing down positive) and the commanded angle of attack alpha
    and sideslip beta (rad; those of v_b once the settle blend is over)."""
    q: np.ndarray
    c_na: np.ndarray
    w_na: np.ndarray
    v_n: np.ndarray
    a_n: np.ndarray
    v_b: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    h: np.ndarray
    p_w: np.ndarray
    mu: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray


class FlightPath:
    """The flight from scenario time tau_start through the segments, starting at the ENU
    velocity v_start and world position p_start. With the deck attitude q_rel and body rate
    w_rel at the release the attitude settles from them (settle_s); without (an airborne start)
    it is the flight attitude from the start."""

    def __init__(self, cfg: FlightConfig, plane: earth.TangentPlane, tau_start: float,
                 v_start: np.ndarray, p_start: np.ndarray,
                 q_rel: np.ndarray | None = None, w_rel: np.ndarray | None = None) -> None:
        self.cfg = cfg
        self.plane = plane
        self.t0 = float(tau_start)
        lat, lon, h = plane.to_geodetic(np.asarray(p_start, dtype=float))
        self.lat0, self.lon0, self.h0 = float(lat), float(lon), float(h)
        self.alpha = cfg.alpha_deg * DEG
        v = np.asarray(v_start, dtype=float)
        vh0 = math.hypot(v[0], v[1])
        if vh0 < 1.0:
            raise ConfigError(f"aircraft.flight: the release ground speed is {vh0:.3g} m/s; "
                              "a flight needs the catapult to launch the aircraft")
        self._schedule(cfg.parsed(), vh0, float(v[2]), math.atan2(v[1], v[0]))
        self.settle = q_rel is not None
        if self.settle:                          # attitude blend from the deck attitude at the release
            m = self._model(np.zeros(1))
            self.delta0 = quat_to_rotvec(quat_mul(quat_conj(m['q'][0]), np.asarray(q_rel, dtype=float)))
            e0 = rotvec_to_dcm_batch(self.delta0)
            self.delta_rate0 = np.linalg.solve(right_jacobian(self.delta0), np.asarray(w_rel, dtype=float)
                                               - e0.T @ m['w'][0])
        else:
            self.delta0 = self.delta_rate0 = np.zeros(3)
        # position grid (lat, lon and their rates), extended on demand
        self._lat = np.array([self.lat0])
        self._lon = np.array([self.lon0])
        self._dlat = np.empty(0)
        self._dlon = np.empty(0)
        rel = ([self.cfg.settle_s] if self.settle else []) + list(self.t_start[1:]) + list(self.t_start + self.T)
        self.breakpoints = self.t0 + np.unique([t for t in rel if 0.0 < t < np.inf])

    # ----- schedule -----
    def _schedule(self, segs, vh0: float, vu0: float, chi0: float) -> None:
        n = max(len(segs), 1)
        t_start, T = np.zeros(n), np.full(n, self.cfg.transition_s)
        q_from, q_to = np.zeros((n, 3)), np.zeros((n, 3))          # (V_h, v_U, chi')
        a_from, a_to = np.zeros((n, 2)), np.zeros((n, 2))          # (alpha, beta)
        air = np.array([self.alpha, 0.0])
        chi_start, h_start = np.zeros(n), np.zeros(n)
        t, q, chi, h = 0.0, np.array([vh0, vu0, 0.0]), chi0, self.h0
        if not segs:                                               # not reached: '' = legacy free flight
            segs = (FlightSegment('level'),)
        for i, s in enumerate(segs):
            where = f"aircraft.flight.segments[{i}] ({s.kind})"
            T[i] = s.transition_s if s.transition_s is not None else self.cfg.transition_s
            speed = s.speed_mps if s.speed_mps is not None else math.hypot(q[0], q[1])
            target = np.array([air[0] if s.alpha_deg is None else s.alpha_deg * DEG,
                               air[1] if s.beta_deg is None else s.beta_deg * DEG])
            if s.climb_rate_mps is not None:
                if abs(s.climb_rate_mps) >= speed:
                    raise ConfigError(f"{where}: |climb_rate_mps| = {abs(s.climb_rate_mps)} must be "
                                      f"below the speed {speed:.4g} m/s")
                vu = s.climb_rate_mps
                vh = math.sqrt(speed * speed - vu * vu)
            elif s.flight_path_deg is not None or s.pitch_deg is not None:
                gam = s.flight_path_deg * DEG if s.flight_path_deg is not None else s.pitch_deg * DEG - target[0]
                vh, vu = speed * math.cos(gam), speed * math.sin(gam)
            else:
                vh, vu = speed, 0.0
            if s.bank_deg is not None:
                g, _ = gravity_and_height_rate(self.lat0, np.array(h))
                w = -float(g) * math.tan(s.bank_deg * DEG) / speed
            elif s.turn_rate_dps is not None:
                w = -s.turn_rate_dps * DEG
            else:
                w = 0.0
            t_start[i], chi_start[i], h_start[i] = t, chi, h
            q_from[i], q_to[i] = q, (vh, vu, w)
            a_from[i], a_to[i] = air, target
            air = target
            if s.duration_s > 0.0 and i < len(segs) - 1:
                _, _, _, integ = self._blend(np.array([s.duration_s]), T[i], q_from[i], q_to[i])
                chi, h = chi + integ[0, 2], h + integ[0, 1]
                t += s.duration_s
            q = q_to[i].copy()
        self.segments = segs
        self.t_start, self.T, self.q_from, self.q_to = t_start, T, q_from, q_to
        self.chi_start, self.h_start = chi_start, h_start
        self.a_from, self.a_to = a_from, a_to
        self.air_fixed = all(s.alpha_deg is None and s.beta_deg is None for s in segs)

    @staticmethod
    def _blend(tau, T, q0, q1):
        """Value, first and second derivative and integral since the segment start of the
        blended (V_h, v_U, chi') (or (alpha, beta)) at times tau since the segment start;
        T, q0, q1 per row."""
        T = np.asarray(T, dtype=float)[..., None] if np.ndim(T) else T
        tau = tau[..., None]
        x = np.clip(tau / T, 0.0, 1.0)
        S, S1, S2, I = _smooth(x)
        dq = q1 - q0
        return (q0 + dq * S, dq * S1 / T, dq * S2 / (T * T),
                q0 * tau + dq * (T * I + np.maximum(tau - T, 0.0)))

    def _kinematics(self, t: np.ndarray, air: bool = False) -> dict[str, np.ndarray]:
        """(V_h, v_U, chi') with derivatives, chi and h at flight times t >= 0; with `air`
        also (alpha, beta) and their rates."""
        i = np.clip(np.searchsorted(self.t_start, t, side='right') - 1, 0, len(self.t_start) - 1)
        tau = t - self.t_start[i]
        q, qd, qdd, integ = self._blend(tau, self.T[i], self.q_from[i], self.q_to[i])
        out = {'q': q, 'qd': qd, 'qdd': qdd, 'chi': self.chi_start[i] + integ[..., 2],
               'h': self.h_start[i] + integ[..., 1]}
        if air:
            out['air'], out['aird'], _, _ = self._blend(tau, self.T[i], self.a_from[i], self.a_to[i])
        return out

    def _model(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """Flight attitude (no settle blend), its body rate, velocity and acceleration."""
        k = self._kinematics(t, air=not self.air_fixed)
        (vh, vu, w), (vhd, vud, wd), (vhdd, vudd, _) = (np.moveaxis(k[x], -1, 0) for x in ('q', 'qd', 'qdd'))
        chi, h = k['chi'], k['h']
        V2 = vh * vh + vu * vu
        V = np.sqrt(V2)
        Vd = (vh * vhd + vu * vud) / V
        gam = np.arctan2(vu, vh)
        cg, sg = np.cos(gam), np.sin(gam)
        nn = vh * vud - vu * vhd
        gd = nn / V2
        gdd = (vh * vudd - vu * vhdd) / V2 - 2.0 * nn * Vd / (V2 * V)
        g, dgdh = gravity_and_height_rate(self.lat0, h)
        N = -vh * w
        Nd = -(vhd * w + vh * wd)
        D = V * gd + g * cg
        Dd = Vd * gd + V * gdd + dgdh * vu * cg - g * sg * gd
        mu = np.where(D < 0.0, np.arctan2(-N, -D), np.arctan2(N, D))   # upright below zero g
        mud = (D * Nd - N * Dd) / (N * N + D * D)
        q_path = quat_mul_batch(axis_quat_batch(chi, 2), axis_quat_batch(-gam, 1))
        # velocity-axes rate b: chi' about the nav z, -gamma' about the path y, mu' about x
        a0, a1, a2 = w * sg, -gd, w * cg
        cm, sm = np.cos(mu), np.sin(mu)
        b0, b1, b2 = a0 + mud, cm * a1 + sm * a2, -sm * a1 + cm * a2
        if self.air_fixed:                       # constant alpha, beta = 0: the original floats
            q = quat_mul_batch(q_path, quat_mul_batch(axis_quat_batch(mu, 0),
                                                      axis_quat_batch(np.full_like(mu, -self.alpha), 1)))
            ca, sa = math.cos(self.alpha), math.sin(self.alpha)
            w_m = np.stack([ca * b0 + sa * b2, b1, -sa * b0 + ca * b2], axis=-1)
            alpha, beta = np.full_like(mu, self.alpha), np.zeros_like(mu)
        else:
            (alpha, beta), (ad, bd) = np.moveaxis(k['air'], -1, 0), np.moveaxis(k['aird'], -1, 0)
            q = quat_mul_batch(q_path, quat_mul_batch(axis_quat_batch(mu, 0), quat_mul_batch(
                axis_quat_batch(beta, 2), axis_quat_batch(-alpha, 1))))
            # Ry(alpha) Rz(-beta) b + (sin(alpha) beta', -alpha', cos(alpha) beta')
            cb, sb = np.cos(beta), np.sin(beta)
            u0, u1, u2 = cb * b0 + sb * b1, -sb * b0 + cb * b1, b2 + bd
            ca, sa = np.cos(alpha), np.sin(alpha)
            w_m = np.stack([ca * u0 + sa * u2, u1 - ad, -sa * u0 + ca * u2], axis=-1)
        cc, sc = np.cos(chi), np.sin(chi)
        v_n = np.stack([vh * cc, vh * sc, vu], axis=-1)
        a_n = np.stack([vhd * cc - vh * w * sc, vhd * sc + vh * w * cc, vud], axis=-1)
        return {'q': q, 'w': w_m, 'v_n': v_n, 'a_n': a_n, 'h': h, 'mu': mu, 'alpha': alpha, 'beta': beta}

    # ----- position -----
    def _extend(self) -> None:
        """Add CHUNK_STEPS RK4 steps of (lat, lon) to the grid."""
        j0 = len(self._lat) - 1
        tt = (2 * j0 + np.arange(2 * CHUNK_STEPS + 1)) * (0.5 * GRID_S)
        k = self._kinematics(tt)
        vh = k['q'][:, 0]
        v_e, v_n, hh = (vh * np.cos(k['chi'])).tolist(), (vh * np.sin(k['chi'])).tolist(), k['h'].tolist()
        a, e2 = earth.A, earth.E2

        def rate(lat, m):
            s = math.sin(lat)
            den = 1.0 - e2 * s * s
            sq = math.sqrt(den)
            return v_n[m] / (a * (1.0 - e2) / (den * sq) + hh[m]), v_e[m] / ((a / sq + hh[m]) * math.cos(lat))

        lat, lon = float(self._lat[-1]), float(self._lon[-1])
        H = GRID_S
        lats, lons, dlats, dlons = [], [], [], []
        k1 = rate(lat, 0)
        for m in range(CHUNK_STEPS):
            k2 = rate(lat + 0.5 * H * k1[0], 2 * m + 1)
            k3 = rate(lat + 0.5 * H * k2[0], 2 * m + 1)
            k4 = rate(lat + H * k3[0], 2 * m + 2)
            dlats.append(k1[0])
            dlons.append(k1[1])
            lat += H / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
            lon += H / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
            lats.append(lat)
            lons.append(lon)
            k1 = rate(lat, 2 * m + 2)
        self._lat = np.concatenate([self._lat, lats])
        self._lon = np.concatenate([self._lon, lons])
        self._dlat = np.concatenate([self._dlat, dlats])
        self._dlon = np.concatenate([self._dlon, dlons])
        # rates at every grid point (the last one is the next step's first stage)
        self._dlat_all = np.append(self._dlat, k1[0])
        self._dlon_all = np.append(self._dlon, k1[1])

    def _latlon(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        while len(self._lat) - 1 < np.max(t, initial=0.0) / GRID_S + 2:
            self._extend()
        dlat, dlon = self._dlat_all, self._dlon_all
        j = np.clip(np.floor(t / GRID_S).astype(int), 0, len(self._lat) - 2)
        u = t / GRID_S - j
        h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
        h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
        lat = h00 * self._lat[j] + h10 * GRID_S * dlat[j] + h01 * self._lat[j + 1] + h11 * GRID_S * dlat[j + 1]
        lon = h00 * self._lon[j] + h10 * GRID_S * dlon[j] + h01 * self._lon[j + 1] + h11 * GRID_S * dlon[j + 1]
        return lat, lon

    # ----- the truth -----
    def state(self, tau) -> FlightState:
        """Flight truth at scenario times tau (s; any shape, all >= the release)."""
        tau = np.asarray(tau, dtype=float)
        t = tau - self.t0
        m = self._model(t)
        if self.settle:
            x = np.clip(t / self.cfg.settle_s, 0.0, 1.0)[..., None]
            S, S1, _, _ = _smooth(x)
            h1 = x - 6.0 * x**3 + 8.0 * x**4 - 3.0 * x**5
            h1d = 1.0 - 18.0 * x**2 + 32.0 * x**3 - 15.0 * x**4
            ts = self.cfg.settle_s
            delta = self.delta0 * (1.0 - S) + ts * self.delta_rate0 * h1
            delta_d = -self.delta0 * S1 / ts + self.delta_rate0 * h1d
            q = quat_mul_batch(m['q'], rotvec_to_quat_batch(delta))
            e = rotvec_to_dcm_batch(delta)
            w_na = (np.einsum('...ji,...j->...i', e, m['w'])
                    + np.einsum('...ij,...j->...i', right_jacobian(delta), delta_d))
        else:
            q, w_na = m['q'], m['w']
        c_na = quat_to_dcm_batch(q)
        lat, lon = self._latlon(t)
        h = m['h']
        p_w = self.plane.from_geodetic_rows(lat, lon, h)               # batch = one at a time, bit for bit
        v_b = np.einsum('...ji,...j->...i', c_na, m['v_n'])
        return FlightState(q=q, c_na=c_na, w_na=w_na, v_n=m['v_n'], a_n=m['a_n'], v_b=v_b,
                           lat=lat, lon=lon, h=h, p_w=p_w, mu=m['mu'], alpha=m['alpha'], beta=m['beta'])
