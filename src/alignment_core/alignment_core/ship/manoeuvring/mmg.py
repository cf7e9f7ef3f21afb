"""MMG manoeuvring model (Yasukawa & Yoshimura 2015) in surge, sway, yaw and roll; RK4.

Yasukawa, H., Yoshimura, Y. (2015) Introduction of MMG standard method for ship
maneuvering predictions. J Mar Sci Technol 20:37-52 ("Y&Y" below; equation numbers theirs).

Axes (MMG): origin at midship, x forward, y to starboard, z down; earth axes x0 North,
y0 East, heading psi from North clockwise (= navigational heading), yaw rate r > 0 to
starboard, rudder angle delta > 0 turns the ship to starboard, roll phi > 0 starboard down
(the ROS roll angle). Surge u, sway v at midship (their v_m).

Motion (Y&Y eq 4, centre of gravity at x_G):
  (m + m_x) u' - (m + m_y) v r - x_G m r^2 = X_H + X_R + X_P + X_W + X_E
  (m + m_y) v' + (m + m_x) u r + x_G m r'   = Y_H + Y_R + Y_W + Y_E
  (I_zG + x_G^2 m + J_z) r' + x_G m (v' + u r) = N_H + N_R + N_W + N_E
Hull (eq 8): X_H = 1/2 rho L d U^2 X'_H(v', r'), Y_H likewise, N_H = 1/2 rho L^2 d U^2 N'_H,
  X'_H = -R'_0 + X'_vv v'^2 + X'_vr v' r' + X'_rr r'^2 + X'_vvvv v'^4,
  Y'_H = Y'_v v' + Y'_R r' + Y'_vvv v'^3 + Y'_vvr v'^2 r' + Y'_vrr v' r'^2 + Y'_rrr r'^3 (N' alike),
  v' = v/U, r' = r L/U, U = sqrt(u^2 + v^2).
Propeller (eqs 9-14): X_P = (1 - t_P) rho n^2 D_P^4 K_T(J_P) per propeller, K_T = k0 + k1 J + k2 J^2,
  J_P = u (1 - w_P) / (n D_P), 1 - w_P = (1 - w_P0)(1 + (1 - exp(-C1 |beta_P|))(C2 - 1)),
  beta_P = beta - x'_P r', beta = atan2(-v, u); C2 by the sign of beta_P.
Rudder (eqs 15-27): F_N = 1/2 rho A_R U_R^2 f_alpha sin(alpha_R), alpha_R = delta - atan2(v_R, u_R),
  X_R = -(1 - t_R) F_N sin(delta), Y_R = -(1 + a_H) F_N cos(delta),
  N_R = -(x_R + a_H x_H) F_N cos(delta), v_R = U gamma_R beta_R, beta_R = beta - l'_R r',
  u_R = eps u (1 - w_P) sqrt(eta {1 + kappa (sqrt(1 + 8 K_T / (pi J^2)) - 1)}^2 + 1 - eta),
  written here as u_R = eps sqrt(eta [(1 - kappa) u_P + kappa sqrt(u_P^2 + 8 K_T n^2 D^2/pi)]^2
  + (1 - eta) u_P^2), u_P = (1 - w_P) u (the same for J > 0, finite at J = 0).
Wind (seed 002 eq 8): X_W = 1/2 rho_a A_F V^2 C_X, Y_W = 1/2 rho_a A_L V^2 C_Y,
  N_W = 1/2 rho_a A_L L V^2 C_N, K_W = h Y_W, with the simple coefficient shapes of Fossen
  (2021, Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd ed., Sec. 10.1):
  C_X = -c_x cos(g), C_Y = c_y sin(g), C_N = c_n sin(2 g), g = -atan2(v_rw, u_rw) the angle of
  the relative wind (0: from ahead), (u_rw, v_rw) = ship velocity minus wind velocity.
Roll (our addition; Y&Y's standard method is 3 DOF): a linear oscillator with the heel
  moment of the lateral forces, which does not feed back into surge, sway and yaw:
  phi'' + 2 zeta w phi' + w^2 phi = K / I44, I44 = m g GM / w^2, w = 2 pi / T_roll,
  K = -z_H (Y_H - m_y v' - m_x u r) - z_R Y_R + K_W + K_E,
  z_H, z_R: depth of the hull's and the rudder's lateral force below G (in a steady turn
  K = -z_H m u r + (z_H - z_R) Y_R: outward heel, and inward at the first rudder kick).
X_E, Y_E, N_E, K_E: optional external forces (e.g. `box_ship_waves`).

Presets: `KVLCC2` (full scale) and `KVLCC2_MODEL` (Y&Y's 7 m model, scale 1/45.7) with Y&Y's
Tables 1-3, and `CARRIER` (see its docstring for the origin of every number).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from alignment_core.units import G0

RHO_SEA = 1025.0
RHO_AIR = 1.293          # seed 002 (0 deg C)


@dataclass(frozen=True)
class MmgShip:
    """A ship's MMG particulars. Primed (non-dimensional) coefficients as in Y&Y: forces by
    1/2 rho L d U^2, moments by 1/2 rho L^2 d U^2, masses by 1/2 rho L^2 d, inertia by
    1/2 rho L^4 d; lengths with a prime are fractions of L."""
    name: str
    lpp: float                 # m
    beam: float                # m
    draft: float               # m
    volume: float              # displacement volume, m^3
    x_g: float                 # centre of gravity forward of midship, m
    rho: float = RHO_SEA
    k_zz: float = 0.25         # yaw radius of gyration / L
    # added masses (Y&Y Table 3)
    m_x: float = 0.022
    m_y: float = 0.223
    j_z: float = 0.011
    # hull (Y&Y Table 3)
    r0: float = 0.022
    x_vv: float = -0.040
    x_vr: float = 0.002
    x_rr: float = 0.011
    x_vvvv: float = 0.771
    y_v: float = -0.315
    y_r: float = 0.083
    y_vvv: float = -1.607
    y_vvr: float = 0.379
    y_vrr: float = -0.391
    y_rrr: float = 0.008
    n_v: float = -0.137
    n_r: float = -0.049
    n_vvv: float = -0.030
    n_vvr: float = -0.294
    n_vrr: float = 0.055
    n_rrr: float = -0.013
    # propeller(s) (Y&Y Tables 1, 3)
    n_propellers: int = 1
    d_p: float = 9.86          # m
    t_p: float = 0.220
    w_p0: float = 0.40
    k0: float = 0.2931
    k1: float = -0.2753
    k2: float = -0.1385
    x_p: float = -0.48         # x'_P
    c1: float = 2.0
    c2_plus: float = 1.6       # beta_P > 0
    c2_minus: float = 1.1      # beta_P < 0
    # rudder(s) (Y&Y Tables 1, 3); a_r is the total area of all rudders
    a_r: float = 112.5         # m^2
    h_r: float = 15.80         # rudder span, m
    t_r: float = 0.387
    a_h: float = 0.312
    x_h: float = -0.464        # x'_H
    x_r: float = -0.5          # x'_R
    gamma_r_minus: float = 0.395   # beta_R < 0
    gamma_r_plus: float = 0.640    # beta_R > 0
    l_r: float = -0.710        # l'_R
    epsilon: float = 1.09
    kappa: float = 0.50
    f_alpha: float = 2.747
    rudder_max_deg: float = 35.0
    rudder_rate_dps: float = 2.34  # Y&Y's model 15.8 deg/s at full scale (/sqrt(45.7))
    # roll (our addition)
    gm: float = 5.71           # m (SIMMAN 2008 KVLCC2 condition)
    roll_period_s: float = 20.4
    roll_zeta: float = 0.05
    z_h: float = 8.2           # hull lateral force below G, m
    z_r: float = 8.2           # rudder force below G, m
    # wind (seed 002 eq 8, Fossen 2021 coefficient shapes)
    area_front: float = 1160.0     # m^2
    area_lateral: float = 5100.0   # m^2
    wind_arm: float = 12.0         # centre of the lateral windage above G, m
    c_x: float = 0.7
    c_y: float = 0.825
    c_n: float = 0.125

    @property
    def mass(self) -> float:
        return self.rho * self.volume

    def scaled(self, scale: float, name: str | None = None) -> MmgShip:
        """Froude-scaled copy (lengths x scale; primed coefficients unchanged)."""
        s = scale
        return replace(self, name=name or f'{self.name} x{s:g}', lpp=self.lpp * s,
                       beam=self.beam * s, draft=self.draft * s, volume=self.volume * s**3,
                       x_g=self.x_g * s, d_p=self.d_p * s, a_r=self.a_r * s * s,
                       h_r=self.h_r * s, rudder_rate_dps=self.rudder_rate_dps / math.sqrt(s),
                       gm=self.gm * s, roll_period_s=self.roll_period_s * math.sqrt(s),
                       z_h=self.z_h * s, z_r=self.z_r * s, area_front=self.area_front * s * s,
                       area_lateral=self.area_lateral * s * s, wind_arm=self.wind_arm * s)


# Y&Y Table 1 (full scale): Lpp 320 m, B 58 m, d 20.8 m, volume 312600 m^3, x_G 11.2 m,
# D_P 9.86 m, H_R 15.80 m, A_R 112.5 m^2; Table 3 coefficients are the dataclass defaults.
# Roll and wind are ours: GM 5.71 m (SIMMAN 2008), T_roll from k_xx = 0.4 B with 10 % added
# inertia, z_H = z_R = KG - d/2 with KG 18.6 m; windage of a laden VLCC (A_F ~ B x 20 m).
KVLCC2 = MmgShip(name='KVLCC2', lpp=320.0, beam=58.0, draft=20.8, volume=312600.0, x_g=11.2)
# Y&Y Table 1 model: Lpp 7.00 m, B 1.27 m, d 0.46 m, volume 3.27 m^3, x_G 0.25 m, D_P 0.216 m,
# H_R 0.345 m, A_R 0.0539 m^2; fresh water; rudder rate 15.8 deg/s (Y&Y).
KVLCC2_MODEL = replace(KVLCC2.scaled(7.0 / 320.0, 'KVLCC2 model (Y&Y L7)'), beam=1.27, draft=0.46,
                       volume=3.27, x_g=0.25, d_p=0.216, h_r=0.345, a_r=0.0539, rho=1000.0,
                       rudder_rate_dps=15.8)


def _carrier() -> MmgShip:
    """A ~310 m aircraft carrier. Where each number comes from:
    - Lpp 310 m, B 40.5 m (waterline), d 11.3 m, Cb 0.62 -> volume 87960 m^3; GM 3.0 m,
      natural roll 20 s, zeta 0.05 (0 kn; the ship config may override): docs/ship-motion.md.
    - KG ~ 14 m (KM = KB + BM ~ 0.53 d + B^2 Cwp^2 / (12 d Cb) ~ 17 m, minus GM), hence
      z_H = z_R = KG - d/2 = 8.35 m; lateral windage centre ~13 m above the waterline,
      G 2.7 m above it: wind arm 10 m; windage A_F 2400 m^2, A_L 8500 m^2 (docs/ship-motion.md).
    - Hull derivatives: Y&Y's KVLCC2 values scaled by the slender-body aspect ratio
      (d/L)_carrier / (d/L)_KVLCC2 = 0.0365/0.0650 = 0.561 (linear lift of a low-aspect wing,
      Y'_v ~ pi d/L + ...; the same factor for every Y', N' and the X' cross terms). Added
      masses: m_y/m = 0.78 (KVLCC2 0.77; slender body pi d/(2 Cb B) = 0.71 for both, x1.1),
      J_z/I_z = 0.61 (KVLCC2), m_x/m = 0.05 (fine hull; KVLCC2 0.076). k_zz 0.25 L.
    - Resistance R'_0 = 0.020: effective power ~125 MW at 30 kn (194 MW shaft, eta_D 0.65),
      i.e. C_T ~ 0.005 on a wetted surface of 3.9 L d (Mumford).
    - 4 propellers of 6.4 m (docs/ship-motion.md); w_P0 0.136 and t_P 0.145 from Holtrop & Mennen
      (1982) twin-screw formulas; K_T = 0.55 - 0.35 J - 0.15 J^2, a Wageningen-B-like curve
      for P/D ~ 1.3 (our choice: K_T(0) 0.55, zero thrust at J ~ 1.5); C1, C2 and x'_P from
      KVLCC2 but with C2 the same both ways (twin screws: port/starboard symmetric).
    - 2 rudders of 39 m^2 (total A_R = L d / 45, a typical warship ratio), span 6.5 m
      (eta = D_P/H_R ~ 0.98), f_alpha = 6.13 Lambda / (Lambda + 2.25) with Lambda = 1.08
      (Fujii's formula, as in Y&Y); t_R, a_H, x'_H, l'_R, eps, kappa from KVLCC2, gamma_R
      their mean both ways (symmetric). Rudder 35 deg at 2.5 deg/s (IMO: >= 2.32 deg/s).
    """
    lpp, beam, draft, cb = 310.0, 40.5, 11.3, 0.62
    volume = cb * lpp * beam * draft
    m_prime = volume / (0.5 * lpp**2 * draft)
    f = (draft / lpp) / (20.8 / 320.0)
    k = KVLCC2
    lam = 6.5**2 / 39.0
    return MmgShip(
        name='carrier', lpp=lpp, beam=beam, draft=draft, volume=volume, x_g=0.0,
        m_x=0.05 * m_prime, m_y=0.78 * m_prime, j_z=0.61 * m_prime * 0.25**2,
        r0=0.020, x_vv=k.x_vv * f, x_vr=k.x_vr * f, x_rr=k.x_rr * f, x_vvvv=k.x_vvvv * f,
        y_v=k.y_v * f, y_r=k.y_r * f, y_vvv=k.y_vvv * f, y_vvr=k.y_vvr * f, y_vrr=k.y_vrr * f,
        y_rrr=k.y_rrr * f, n_v=k.n_v * f, n_r=k.n_r * f, n_vvv=k.n_vvv * f, n_vvr=k.n_vvr * f,
        n_vrr=k.n_vrr * f, n_rrr=k.n_rrr * f,
        n_propellers=4, d_p=6.4, t_p=0.145, w_p0=0.136, k0=0.55, k1=-0.35, k2=-0.15, x_p=-0.48,
        c1=2.0, c2_plus=1.35, c2_minus=1.35,
        a_r=lpp * draft / 45.0, h_r=6.5, gamma_r_minus=0.5175, gamma_r_plus=0.5175,
        f_alpha=6.13 * lam / (lam + 2.25), rudder_max_deg=35.0, rudder_rate_dps=2.5,
        gm=3.0, roll_period_s=20.0, roll_zeta=0.05, z_h=8.35, z_r=8.35,
        area_front=2400.0, area_lateral=8500.0, wind_arm=10.0)


CARRIER = _carrier()
SHIPS = {'carrier': CARRIER, 'kvlcc2': KVLCC2}


@dataclass(frozen=True)
class Wind:
    """Steady true wind: speed (m/s) and the direction it comes from (rad, from North,
    clockwise, as weather reports give it)."""
    speed: float = 0.0
    from_dir: float = 0.0


# state layout of MmgModel.rhs
N_STATE = 8
I_N, I_E, I_PSI, I_U, I_V, I_R, I_PHI, I_P = range(N_STATE)


@dataclass
class MmgModel:
    """Forces and accelerations of `ship` (see the module docstring)."""
    ship: MmgShip
    wind: Wind = field(default_factory=Wind)

    def __post_init__(self) -> None:
        s = self.ship
        L, d, rho = s.lpp, s.draft, s.rho
        self.m = s.mass
        self.q_f = 0.5 * rho * L * d                 # x U^2: force scale
        self.q_n = 0.5 * rho * L * L * d             # x U^2: moment scale
        self.mx = s.m_x * 0.5 * rho * L**2 * d
        self.my = s.m_y * 0.5 * rho * L**2 * d
        self.jz = s.j_z * 0.5 * rho * L**4 * d
        self.izg = self.m * (s.k_zz * L) ** 2
        m, xg = self.m, s.x_g
        # [m+my, xg m; xg m, Iz] [v'; r'] = [..]: inverse of the 2x2 matrix
        a11, a12, a22 = m + self.my, xg * m, self.izg + xg * xg * m + self.jz
        det = a11 * a22 - a12 * a12
        self._inv = (a22 / det, -a12 / det, a11 / det)
        self.eta = s.d_p / s.h_r
        self.x_r_m = s.x_r * L
        self.x_h_m = s.x_h * L
        w = 2.0 * math.pi / s.roll_period_s
        self.w_roll = w
        self.i44 = m * G0 * s.gm / (w * w)
        self.thrust_k = s.n_propellers * rho * s.d_p**4

    # --- forces -------------------------------------------------------------------------
    def hull(self, u: float, v: float, r: float) -> tuple[float, float, float]:
        s = self.ship
        U2 = u * u + v * v
        if U2 == 0.0:
            return 0.0, 0.0, 0.0
        U = math.sqrt(U2)
        vp, rp = v / U, r * s.lpp / U
        xh = (-s.r0 + s.x_vv * vp * vp + s.x_vr * vp * rp + s.x_rr * rp * rp + s.x_vvvv * vp**4)
        yh = (s.y_v * vp + s.y_r * rp + s.y_vvv * vp**3 + s.y_vvr * vp * vp * rp
              + s.y_vrr * vp * rp * rp + s.y_rrr * rp**3)
        nh = (s.n_v * vp + s.n_r * rp + s.n_vvv * vp**3 + s.n_vvr * vp * vp * rp
              + s.n_vrr * vp * rp * rp + s.n_rrr * rp**3)
        return self.q_f * U2 * xh, self.q_f * U2 * yh, self.q_n * U2 * nh

    def propeller_rudder(self, u: float, v: float, r: float, delta: float, n: float
                         ) -> tuple[float, float, float, float]:
        """X_P + X_R, Y_R, N_R and the rudder normal force F_N."""
        s = self.ship
        U = math.hypot(u, v)
        if U > 0.0:
            beta = math.atan2(-v, u)
            rp = r * s.lpp / U
        else:
            beta = rp = 0.0
        beta_p = beta - s.x_p * rp
        c2 = s.c2_plus if beta_p > 0.0 else s.c2_minus
        one_w = (1.0 - s.w_p0) * (1.0 + (1.0 - math.exp(-s.c1 * abs(beta_p))) * (c2 - 1.0))
        u_p = one_w * u
        nd = n * s.d_p
        j = u_p / nd if nd != 0.0 else 0.0
        kt = s.k0 + s.k1 * j + s.k2 * j * j
        xp = (1.0 - s.t_p) * self.thrust_k * n * n * kt
        # rudder inflow (Y&Y eq 25 in a form finite at J = 0)
        slip = u_p * u_p + 8.0 * kt * nd * nd / math.pi
        jet = (1.0 - s.kappa) * u_p + s.kappa * math.copysign(math.sqrt(max(slip, 0.0)), u_p)
        u_r = s.epsilon * math.sqrt(self.eta * jet * jet + (1.0 - self.eta) * u_p * u_p)
        beta_r = beta - s.l_r * rp
        gamma = s.gamma_r_plus if beta_r > 0.0 else s.gamma_r_minus
        v_r = U * gamma * beta_r
        alpha = delta - math.atan2(v_r, u_r)
        fn = 0.5 * s.rho * s.a_r * (u_r * u_r + v_r * v_r) * s.f_alpha * math.sin(alpha)
        cd, sd = math.cos(delta), math.sin(delta)
        return (xp - (1.0 - s.t_r) * fn * sd, -(1.0 + s.a_h) * fn * cd,
                -(self.x_r_m + s.a_h * self.x_h_m) * fn * cd, fn)

    def wind_forces(self, u: float, v: float, psi: float) -> tuple[float, float, float, float]:
        """X_W, Y_W, N_W, K_W of the steady wind for the ship's velocity and heading."""
        w = self.wind
        if w.speed == 0.0:
            return 0.0, 0.0, 0.0, 0.0
        s = self.ship
        to = w.from_dir + math.pi - psi                  # wind velocity direction, ship axes
        u_rw = u - w.speed * math.cos(to)
        v_rw = v - w.speed * math.sin(to)
        g = -math.atan2(v_rw, u_rw)
        q = 0.5 * RHO_AIR * (u_rw * u_rw + v_rw * v_rw)
        yw = q * s.area_lateral * s.c_y * math.sin(g)
        return (-q * s.area_front * s.c_x * math.cos(g), yw,
                q * s.area_lateral * s.lpp * s.c_n * math.sin(2.0 * g), s.wind_arm * yw)

    # --- equations of motion --------------------------------------------------------------
    def rhs(self, y, delta: float, n: float, ext=(0.0, 0.0, 0.0, 0.0)) -> list[float]:
        """d/dt of the state [N, E, psi, u, v, r, phi, p] (m, m, rad, m/s, m/s, rad/s, rad,
        rad/s) for rudder angle delta (rad), propeller revs n (1/s) and external forces
        ext = (X, Y, N, K)."""
        s = self.ship
        psi, u, v, r, phi, p = y[2], y[3], y[4], y[5], y[6], y[7]
        xh, yh, nh = self.hull(u, v, r)
        xpr, yr, nr, _ = self.propeller_rudder(u, v, r, delta, n)
        xw, yw, nw, kw = self.wind_forces(u, v, psi)
        m, xg = self.m, s.x_g
        X = xh + xpr + xw + ext[0]
        Y = yh + yr + yw + ext[1]
        N = nh + nr + nw + ext[2]
        du = (X + (m + self.my) * v * r + xg * m * r * r) / (m + self.mx)
        b1 = Y - (m + self.mx) * u * r
        b2 = N - xg * m * u * r
        i11, i12, i22 = self._inv
        dv = i11 * b1 + i12 * b2
        dr = i12 * b1 + i22 * b2
        k = -s.z_h * (yh - self.my * dv - self.mx * u * r) - s.z_r * yr + kw + ext[3]
        w = self.w_roll
        dp = k / self.i44 - 2.0 * s.roll_zeta * w * p - w * w * phi
        cp, sp = math.cos(psi), math.sin(psi)
        return [u * cp - v * sp, u * sp + v * cp, r, du, dv, dr, p, dp]

    def equilibrium_revs(self, speed: float) -> float:
        """Propeller revs (1/s) that hold `speed` straight ahead in calm air and water:
        the positive root of (1 - t_P) K rho D^4 (k0 n^2 + k1 n a/D + k2 a^2/D^2)
        = 1/2 rho L d R'_0 U^2, a = (1 - w_P0) U (K propellers; X_R = 0 at delta = 0)."""
        s = self.ship
        if speed <= 0.0:
            return 0.0
        a = (1.0 - s.w_p0) * speed / s.d_p
        rhs = self.q_f * s.r0 * speed * speed / ((1.0 - s.t_p) * self.thrust_k)
        qa, qb, qc = s.k0, s.k1 * a, s.k2 * a * a - rhs
        return (-qb + math.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa)


def rk4_step(f, t: float, y: list[float], h: float) -> tuple[list[float], list[float]]:
    """One classical Runge-Kutta step of y' = f(t, y) on plain lists (small systems: lists
    beat numpy here); returns (y(t + h), f(t, y))."""
    k1 = f(t, y)
    k2 = f(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k1)])
    k3 = f(t + 0.5 * h, [a + 0.5 * h * b for a, b in zip(y, k2)])
    k4 = f(t + h, [a + h * b for a, b in zip(y, k3)])
    h6 = h / 6.0
    return [a + h6 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
            for a, b1, b2, b3, b4 in zip(y, k1, k2, k3, k4)], k1
