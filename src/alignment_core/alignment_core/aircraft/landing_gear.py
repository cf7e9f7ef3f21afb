"""The airframe on its landing gear: a 9-degree-of-freedom model about the static point, linear
but for the polytropic air springs' excess over their tangent.

Generalised coordinates q (9,), all relative to the static equilibrium on a level deck at rest,
in the airframe's axes on deck (FLU, the deck turned by the heading on deck):
    q = [d (3): CG displacement, theta (3): small rotation vector, z_u (3): axle heave of the
         nose, left main and right main legs]
Each leg has a contact point p_i (from the CG, on the tyre contact plane, cg_height_m below
the CG). The airframe moves that point by u_i = d + theta x p_i. Elements:
- strut (oleo): vertical spring k_s and damper c_s between the airframe at leg i (u_i,z) and
  its axle (z_u,i); k_s = n F_i / L_gas (the polytropic air spring's slope at the static load
  F_i, the lever rule's share of the airframe's weight);
- tyre, vertical: spring and damper between the axle and the deck;
- tyre, longitudinal and lateral: springs and dampers between the airframe at the contact
  point (u_i,x, u_i,y) and the deck (the strut is taken rigid fore-aft and sideways).
- gravity's geometric stiffness: a roll or pitch theta of the airframe shifts the contact
  points by theta x p_i under the static leg loads, a moment m g h theta that helps the
  rotation (-m g h on K's roll and pitch diagonal; h = cg_height_m).
Then M q'' + C q' + K q = f(t), with f the generalised forces: the deck's motion felt as
inertial loads in the deck frame, gusts, the hold-back pull (aircraft/gear_response.py).
Gyroscopic and Coriolis terms of the deck's rotation (|omega| ~ 0.01 rad/s) are neglected.

With f linear between samples (first-order hold) the response is exact at the samples:
x_(k+1) = Phi x_k + G0 f_k + G1 f_(k+1), x = [q, q'] (18,), from one matrix exponential.
With `strut_spring: polytropic` the air springs' force beyond their tangent at the static
point, F0 ((1 - s / L)^-n - 1 - n s / L) for a compression s, joins f as a load of the state
(gear_response.py steps it by a predictor-corrector).
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from alignment_core.aircraft.gear_config import GearConfig
from alignment_core.compiled import kernel
from alignment_core.geometry.rotations import skew
from alignment_core.units import G0
from alignment_core.validation import ConfigError

LEGS = ('nose', 'main_left', 'main_right')
N_DOF = 9


BOTTOMING = ("aircraft.gear: a strut compressed to within 5 % of its gas column (bottoming out): "
             "beyond the air spring model")


@kernel
def air_spring_excess_rows(compression, gas, leg_load, n):
    """The polytropic excess F0 ((1 - s / L)^-n - 1 - n s / L) (m, 3) of compressions s (m, 3),
    gas columns L (3,), static loads F0 (3,), index n; ValueError if any s / L >= 0.95.
    Element by element with the C library's pow (numpy's SIMD pow differs in the last bit)."""
    m = compression.shape[0]
    x = np.empty((m, 3))
    for i in range(m):
        for j in range(3):
            x[i, j] = compression[i, j] / gas[j]
    for i in range(m):
        for j in range(3):
            if x[i, j] >= 0.95:
                raise ValueError(BOTTOMING)
    out = np.empty((m, 3))
    for i in range(m):
        for j in range(3):
            out[i, j] = leg_load[j] * ((1.0 - x[i, j]) ** -n - 1.0 - n * x[i, j])
    return out


def _airframe_rows(p: np.ndarray) -> np.ndarray:
    """(3, 9): the displacement d + theta x p of the airframe point p (3,) from q."""
    j = np.zeros((3, N_DOF))
    j[:, :3] = np.eye(3)
    j[:, 3:6] = -skew(p)
    return j


class GearModel:
    """Mass, damping and stiffness matrices (9, 9) of the airframe on its gear, and its loads.

    Attributes: contact (3, 3) contact points from the CG (rows: nose, left main, right main);
    leg_load_n (3,) static strut loads (the airframe's weight by the lever rule);
    strut_k, strut_c, tyre_kz, tyre_kx, tyre_ky, tyre_cz, tyre_cx, tyre_cy, unsprung (3,) each.
    """

    def __init__(self, cfg: GearConfig) -> None:
        self.cfg = cfg
        m, f, wb, h = cfg.mass_kg, cfg.nose_load_fraction, cfg.wheelbase_m, cfg.cg_height_m
        x_main, x_nose, y = -f * wb, (1.0 - f) * wb, 0.5 * cfg.main_track_m
        self.contact = np.array([[x_nose, 0.0, -h], [x_main, y, -h], [x_main, -y, -h]])
        self.leg_load_n = m * G0 * np.array([f, 0.5 * (1.0 - f), 0.5 * (1.0 - f)])
        sprung = self.leg_load_n / G0                                   # mass each leg carries, kg
        gas = np.array([cfg.nose_gas_length_m, cfg.main_gas_length_m, cfg.main_gas_length_m])
        self.strut_k = cfg.polytropic_index * self.leg_load_n / gas
        self.strut_c = 2.0 * cfg.strut_damping_ratio * np.sqrt(self.strut_k * sprung)

        def per_leg(nose: float, main: float) -> np.ndarray:
            return np.array([nose, main, main])
        self.tyre_kz = per_leg(cfg.nose_tyre_kz_npm, cfg.main_tyre_kz_npm)
        self.tyre_kx = per_leg(cfg.nose_tyre_kx_npm, cfg.main_tyre_kx_npm)
        self.tyre_ky = per_leg(cfg.nose_tyre_ky_npm, cfg.main_tyre_ky_npm)
        zt = 2.0 * cfg.tyre_damping_ratio
        self.tyre_cz, self.tyre_cx, self.tyre_cy = (zt * np.sqrt(k * sprung)
                                                    for k in (self.tyre_kz, self.tyre_kx, self.tyre_ky))
        self.unsprung = per_leg(cfg.nose_unsprung_kg, cfg.main_unsprung_kg)
        self.inertia = np.asarray(cfg.inertia_kgm2, dtype=float)
        self.M = np.diag(np.concatenate([np.full(3, m), self.inertia, self.unsprung]))
        self.strut_rows = np.array([self._strut_row(i, p) for i, p in enumerate(self.contact)])   # (3, 9)
        self.gas = gas
        self.polytropic = cfg.strut_spring == 'polytropic'
        self.K_elastic, self.C = self._assemble()
        self.K = self.K_elastic.copy()
        self.K[3, 3] -= m * G0 * h
        self.K[4, 4] -= m * G0 * h
        if np.any(np.linalg.eigvalsh(self.K) <= 0.0):
            raise ConfigError("aircraft.gear: the gear is not stable (roll or pitch stiffness below m g h): "
                             "widen the track or wheelbase, stiffen the struts or lower the CG")

    @staticmethod
    def _strut_row(i: int, p: np.ndarray) -> np.ndarray:
        """(9,): the strut's extension (airframe up relative to its axle) of leg i from q."""
        row = _airframe_rows(p)[2].copy()
        row[6 + i] = -1.0
        return row

    def _assemble(self) -> tuple[np.ndarray, np.ndarray]:
        k = np.zeros((N_DOF, N_DOF))
        c = np.zeros((N_DOF, N_DOF))
        for i, p in enumerate(self.contact):
            rows = _airframe_rows(p)
            strut = self.strut_rows[i]
            k += self.strut_k[i] * np.outer(strut, strut)
            c += self.strut_c[i] * np.outer(strut, strut)
            axle = np.zeros(N_DOF)
            axle[6 + i] = 1.0
            k += self.tyre_kz[i] * np.outer(axle, axle)
            c += self.tyre_cz[i] * np.outer(axle, axle)
            for row, kk, cc in ((rows[0], self.tyre_kx[i], self.tyre_cx[i]),
                                (rows[1], self.tyre_ky[i], self.tyre_cy[i])):
                k += kk * np.outer(row, row)
                c += cc * np.outer(row, row)
        return k, c

    # --- loads (generalised forces, (9,) or (..., 9)) -------------------------------------------
    def gravity_load(self, g: float = G0) -> np.ndarray:
        """The weight of the airframe and the axles (the load whose equilibrium is q = 0)."""
        f = np.zeros(N_DOF)
        f[2] = -self.cfg.mass_kg * g
        f[6:] = -self.unsprung * g
        return f

    def inertial_load(self, specific_force: np.ndarray, wdot: np.ndarray, f0: np.ndarray) -> np.ndarray:
        """Loads (..., 9) of the deck's motion in the deck frame: -m (f - f0) on the airframe and
        on each axle (vertical part), -I wdot on the airframe's rotation; specific_force (..., 3)
        at the CG of the rigidly mounted airframe, wdot (..., 3) the deck's angular acceleration,
        both in airframe axes; f0 (3,) the specific force of the static point."""
        df = np.asarray(specific_force) - f0
        out = np.empty(df.shape[:-1] + (N_DOF,))
        out[..., :3] = -self.cfg.mass_kg * df
        out[..., 3:6] = -self.inertia * np.asarray(wdot)
        out[..., 6:] = -self.unsprung * df[..., 2:3]
        return out

    def point_load(self, force: np.ndarray, point: np.ndarray) -> np.ndarray:
        """Generalised force (9,) of a force (3,) applied to the airframe at point (3,) from the CG."""
        out = np.zeros(N_DOF)
        out[:3] = force
        out[3:6] = np.cross(point, force)
        return out

    def holdback_load(self) -> np.ndarray:
        """Generalised force (9,) per newton of hold-back tension: a forward pull at the nose leg,
        holdback_height_m above the deck."""
        p = self.contact[0] + np.array([0.0, 0.0, self.cfg.holdback_height_m])
        return self.point_load(np.array([1.0, 0.0, 0.0]), p)

    def gust_matrix(self) -> np.ndarray:
        """(9, 3): generalised force per m/s of gust (u: more headwind, v: air moving left, w: air
        moving up), linearised about the wind over the deck V from ahead: with q = rho V^2 / 2,
        alpha = w / V, beta = v / V, the dynamic pressure rises by rho V u."""
        c = self.cfg
        rho, v, s, b, cb = c.air_density_kgpm3, c.wind_over_deck_mps, c.wing_area_m2, c.wing_span_m, c.mean_chord_m
        qv = 0.5 * rho * v * s                                   # q S / V: per m/s of gust, per unit slope
        out = np.zeros((N_DOF, 3))
        out[0, 0] = -rho * v * s * c.drag_coefficient           # drag grows with the headwind
        out[2, 0] = rho * v * s * c.lift_coefficient
        out[2, 2] = qv * c.lift_slope_per_rad                    # lift from the gust's angle of attack
        out[1, 1] = qv * c.side_force_slope_per_rad              # pushed along with the air
        out[3, 1] = -qv * b * c.roll_moment_slope_per_rad        # dihedral effect: lee wing down
        out[4, 2] = qv * cb * c.pitch_moment_slope_per_rad       # static stability: nose down
        out[5, 1] = -qv * b * c.yaw_moment_slope_per_rad         # weathercock: nose into the wind
        return out

    # --- responses ------------------------------------------------------------------------------
    def static(self, load: np.ndarray) -> np.ndarray:
        """q (9,) in equilibrium under a constant load (9,) added to the static one (Newton's
        method with the polytropic springs)."""
        q = np.linalg.solve(self.K, load)
        if not self.polytropic:
            return q
        n, L = self.cfg.polytropic_index, self.gas
        for _ in range(50):
            resid = self.K @ q - self.nonlinear_load(q) - load
            x = self.strut_compression(q) / L
            slope = self.leg_load_n * n / L * ((1.0 - x) ** (-n - 1.0) - 1.0)   # d(excess)/d(compression)
            jac = self.K + (self.strut_rows.T * slope) @ self.strut_rows
            step = np.linalg.solve(jac, resid)
            q = q - step
            if np.abs(step).max() < 1e-13:
                break
        return q

    def settling(self, g: float = G0) -> np.ndarray:
        """q (9,) of the unloaded gear (extended struts, round tyres) relative to the static
        point: minus the deflection the weight causes (elastic stiffness: the legs' preload,
        whose geometric stiffness K holds, builds up along the way)."""
        return -np.linalg.solve(self.K_elastic, self.gravity_load(g))

    def strut_compression(self, q: np.ndarray) -> np.ndarray:
        """Strut shortening (..., 3) from the static point (airframe down relative to its axle: positive)."""
        return -np.asarray(q) @ self.strut_rows.T

    def air_spring_excess(self, compression: np.ndarray) -> np.ndarray:
        """Polytropic strut force beyond its tangent at the static point (..., 3), N (compression
        positive): F0 ((1 - s / L)^-n - 1 - n s / L); zero for the linear spring."""
        if not self.polytropic:
            return np.zeros(np.shape(compression))
        s = np.asarray(compression, dtype=float)
        rows = np.ascontiguousarray(s.reshape(-1, 3))
        out = air_spring_excess_rows(rows, self.gas, self.leg_load_n, float(self.cfg.polytropic_index))
        return out.reshape(s.shape)

    def nonlinear_load(self, q: np.ndarray) -> np.ndarray:
        """Generalised force (..., 9) of the air springs' excess over their linear part."""
        return self.air_spring_excess(self.strut_compression(q)) @ self.strut_rows

    def air_spring_energy(self, q: np.ndarray) -> np.ndarray:
        """Potential energy (...) of the air springs' excess (J): the integral of the excess force."""
        if not self.polytropic:
            return np.zeros(np.shape(q)[:-1])
        s = self.strut_compression(q)
        n, L = self.cfg.polytropic_index, self.gas
        x = s / L
        return (self.leg_load_n * L * (((1.0 - x) ** (1.0 - n) - 1.0) / (n - 1.0) - x - 0.5 * n * x * x)).sum(axis=-1)

    def state_space(self) -> tuple[np.ndarray, np.ndarray]:
        """A (18, 18) and B (18, 9) of x' = A x + B f, x = [q, q']."""
        minv = np.diag(1.0 / np.diag(self.M))
        a = np.zeros((2 * N_DOF, 2 * N_DOF))
        a[:N_DOF, N_DOF:] = np.eye(N_DOF)
        a[N_DOF:, :N_DOF] = -minv @ self.K
        a[N_DOF:, N_DOF:] = -minv @ self.C
        b = np.zeros((2 * N_DOF, N_DOF))
        b[N_DOF:] = minv
        return a, b

    def discretise(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Phi, G0, G1): the exact step over dt with the load linear between its end values."""
        a, b = self.state_space()
        n, m = a.shape[0], b.shape[1]
        z = np.zeros((n + 2 * m, n + 2 * m))
        z[:n, :n] = a * dt
        z[:n, n:n + m] = b * dt
        z[n:n + m, n + m:] = np.eye(m)
        e = expm(z)
        phi, p, r = e[:n, :n], e[:n, n:n + m], e[:n, n + m:]
        return phi, p - r, r

    def acceleration(self, q: np.ndarray, qd: np.ndarray, load: np.ndarray) -> np.ndarray:
        """q'' (..., 9) from the equations of motion (load: the external one; the air springs'
        excess is added here)."""
        return (load + self.nonlinear_load(q) - qd @ self.C.T - q @ self.K.T) / np.diag(self.M)

    def energy(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Kinetic plus elastic energy (J) about the static point."""
        return (0.5 * (np.einsum('...i,ij,...j->...', qd, self.M, qd) + np.einsum('...i,ij,...j->...', q, self.K, q))
                + self.air_spring_energy(q))

    def natural_frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies (9,), ascending."""
        w2 = np.linalg.eigvals(np.linalg.solve(self.M, self.K)).real
        return np.sort(np.sqrt(np.maximum(w2, 0.0))) / (2.0 * np.pi)

    def point_rows(self, p: np.ndarray) -> np.ndarray:
        """(3, 9): displacement of the airframe point p (3,) from q (for the IMU's position)."""
        return _airframe_rows(np.asarray(p, dtype=float))
