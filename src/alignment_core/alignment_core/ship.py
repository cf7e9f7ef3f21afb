"""Ship six-DOF truth at the master INS point.

Two modes (`ShipConfig.mode`): 'paper' (below) and 'spectral' (`ship_waves.py`: a random
sea through response amplitude operators on a straight course; see that module).
`make_motion(cfg, seed)` builds either.

Paper mode (seed 002, eq 18): one sinusoid per attitude axis plus heave, on a straight
course at constant speed. Amplitudes are the paper's Table 3 (sea states 3-7); the paper
gives no periods, so roll sits at the natural roll period and pitch, heave and yaw at the
encounter period of a 175 m ship (`ship-motion.md`); phases are random per axis. Heave
amplitude is half the sea state's mean significant wave height (a regular wave of that
height, heave RAO ~ 1 at these periods).

Truth is INS grade: body rates from Euler rates through the kinematic matrix, angular
acceleration by its exact derivative, and the nav-frame acceleration of the ground velocity.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from . import earth
from .attitude import DEG, euler_acc_to_body_acc, euler_rates_to_body_rate, heading_to_yaw
from .config import ConfigError, require
from .rng import stage_rng
from .samples import ShipSample

KNOT = 0.514444

# seed 002, Table 3: amplitudes (deg) roll, pitch, yaw by sea state
PAPER_AMPLITUDE_DEG = {3: (1.25, 1.01, 1.03), 4: (2.71, 1.71, 1.92), 5: (5.62, 2.91, 3.36),
                       6: (7.47, 3.15, 4.15), 7: (9.84, 5.27, 6.11)}
# periods (s) roll, pitch, yaw, heave for a 175 m ship (ship-motion.md)
PAPER_PERIOD_S = {3: (17.0, 6.5, 8.0, 7.0), 4: (17.0, 7.0, 8.5, 7.5), 5: (17.0, 7.5, 9.0, 8.0),
                  6: (17.0, 7.75, 9.25, 8.5), 7: (18.5, 8.0, 9.5, 9.0)}
# Bales (1983) mean significant wave height (m) by sea state
BALES_HS_M = {0: 0.0, 1: 0.05, 2: 0.3, 3: 0.88, 4: 1.88, 5: 3.25, 6: 5.0, 7: 7.5, 8: 11.5, 9: 14.0}


@dataclass(frozen=True)
class ShipConfig:
    """Ship scenario: course, speed, start position and the sea.

    Spectral mode only (ignored by 'paper'): `hs_m` / `tp_s` override the sea state's
    significant wave height and peak period (0 = Bales table value for `sea_state`);
    `sea_draw` draws them at random within the sea state's bin instead (Monte Carlo);
    `spectrum` ITTC (Bretschneider) or JONSWAP (`jonswap_gamma`); `spreading` 'none'
    (long-crested) or 'cos2' over `n_directions`; `wave_heading_deg` is the direction the
    waves travel relative to the bow, clockwise (180 = head seas, 90 = waves from port,
    0 = following); `n_frequencies` log-spaced bins on `omega_min`..`omega_max` rad/s (0 = auto);
    `rao_source` 'closed_form' (a 310 m carrier, `rao.CarrierParams`, with `roll_period_s` and
    `roll_zeta` (0 = 0.05 at 0 kn to 0.10 at 30 kn)) or a path to an MSS vessel .mat file;
    `course_keeping` 'straight' (constant course and speed; the only low-frequency model yet).
    """
    mode: Literal['paper', 'spectral'] = 'paper'
    sea_state: int = 4
    speed_kn: float = 10.0
    heading_deg: float = 30.0
    lat_deg: float = 40.0
    lon_deg: float = 116.0
    heave: bool = True
    motion_scale: float = 1.0
    hs_m: float = 0.0
    tp_s: float = 0.0
    sea_draw: bool = False
    spectrum: Literal['ittc', 'jonswap'] = 'ittc'
    jonswap_gamma: float = 3.3
    spreading: Literal['none', 'cos2'] = 'cos2'
    wave_heading_deg: float = 180.0
    n_frequencies: int = 150
    n_directions: int = 15
    omega_min: float = 0.0
    omega_max: float = 0.0
    rao_source: str = 'closed_form'
    roll_period_s: float = 20.0
    roll_zeta: float = 0.0
    course_keeping: Literal['straight'] = 'straight'

    def validate(self) -> None:
        require(0 <= self.sea_state <= 9, f"sea_state must be a WMO code 0-9, got {self.sea_state}")
        if self.mode == 'paper':
            require(self.sea_state in PAPER_AMPLITUDE_DEG or self.sea_state == 0,
                    f"paper mode has amplitudes for sea states 3-7 (seed 002 Table 3) "
                    f"and 0 (calm), got {self.sea_state}")
        require(0.0 <= self.speed_kn <= 40.0, f"speed_kn must be in [0, 40], got {self.speed_kn}")
        require(-90.0 < self.lat_deg < 90.0, f"lat_deg must be in (-90, 90), got {self.lat_deg}")
        require(-180.0 <= self.lon_deg <= 360.0, f"lon_deg out of range: {self.lon_deg}")
        require(0.0 <= self.motion_scale <= 10.0, f"motion_scale must be in [0, 10], got {self.motion_scale}")
        require(0.0 <= self.hs_m <= 30.0, f"hs_m must be in [0, 30] m (0 = from sea_state), got {self.hs_m}")
        require(self.tp_s == 0.0 or 1.0 <= self.tp_s <= 30.0,
                f"tp_s must be 0 (from sea_state) or in [1, 30] s, got {self.tp_s}")
        require(1.0 <= self.jonswap_gamma <= 10.0, f"jonswap_gamma must be in [1, 10], got {self.jonswap_gamma}")
        require(-360.0 <= self.wave_heading_deg <= 360.0,
                f"wave_heading_deg must be in [-360, 360], got {self.wave_heading_deg}")
        require(1 <= self.n_frequencies <= 2000, f"n_frequencies must be in [1, 2000], got {self.n_frequencies}")
        require(1 <= self.n_directions <= 101, f"n_directions must be in [1, 101], got {self.n_directions}")
        require(self.omega_min >= 0.0 and self.omega_max >= 0.0,
                f"omega_min / omega_max must be >= 0 (0 = auto), got {self.omega_min}, {self.omega_max}")
        require(self.omega_min == 0.0 or self.omega_max == 0.0 or self.omega_min < self.omega_max,
                f"omega_min must be below omega_max, got {self.omega_min}, {self.omega_max}")
        require(5.0 <= self.roll_period_s <= 60.0, f"roll_period_s must be in [5, 60], got {self.roll_period_s}")
        require(0.0 <= self.roll_zeta < 1.0, f"roll_zeta must be in [0, 1) (0 = speed dependent), got {self.roll_zeta}")
        if self.mode == 'spectral' and self.rao_source != 'closed_form':
            path = os.path.expandvars(os.path.expanduser(self.rao_source))
            require(os.path.isfile(path), f"rao_source: RAO file not found: {self.rao_source!r} "
                                          f"(give 'closed_form' or the path of an MSS vessel .mat file)")


def make_motion(cfg: ShipConfig, seed: int):
    """The ship model for `cfg.mode`: PaperShipMotion or ship_waves.SpectralShipMotion."""
    if cfg.mode == 'paper':
        return PaperShipMotion(cfg, seed)
    if cfg.mode == 'spectral':
        from .ship_waves import SpectralShipMotion
        return SpectralShipMotion(cfg, seed)
    raise ConfigError(f"ship.mode {cfg.mode!r} is not available")


class PaperShipMotion:
    """Seed-002 sinusoidal ship, evaluated analytically at any time (s since scenario start)."""

    def __init__(self, cfg: ShipConfig, seed: int) -> None:
        if cfg.mode != 'paper':
            raise ConfigError(f"ship.mode {cfg.mode!r} is not available")
        self.cfg = cfg
        rng = stage_rng(seed, 'ship')
        if cfg.sea_state == 0:
            amp = np.zeros(3)
            per = np.array([20.0, 10.0, 10.0, 10.0])
            heave = 0.0
        else:
            amp = np.array(PAPER_AMPLITUDE_DEG[cfg.sea_state]) * DEG
            per = np.array(PAPER_PERIOD_S[cfg.sea_state])
            heave = 0.5 * BALES_HS_M[cfg.sea_state] if cfg.heave else 0.0
        s = cfg.motion_scale
        self.amp = amp * s                      # roll, pitch, yaw amplitudes (rad)
        self.heave_amp = heave * s              # m
        self.omega = 2.0 * np.pi / per          # roll, pitch, yaw, heave (rad/s)
        self.phase = rng.uniform(0.0, 2.0 * np.pi, size=4)
        self.yaw0 = heading_to_yaw(cfg.heading_deg * DEG)
        hd = cfg.heading_deg * DEG
        self.v_course = cfg.speed_kn * KNOT * np.array([np.sin(hd), np.cos(hd), 0.0])
        self.lat0 = cfg.lat_deg * DEG
        self.lon0 = cfg.lon_deg * DEG
        self.plane = earth.TangentPlane(self.lat0, self.lon0, 0.0)

    def euler(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """ROS Euler angles (roll, pitch, yaw), their first and second derivatives; (N, 3)."""
        arg = np.outer(t, self.omega[:3]) + self.phase[:3]
        e = self.amp * np.sin(arg)
        ed = self.amp * self.omega[:3] * np.cos(arg)
        edd = -self.amp * self.omega[:3] ** 2 * np.sin(arg)
        e[:, 2] += self.yaw0
        return e, ed, edd

    def heave(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        arg = self.omega[3] * t + self.phase[3]
        w = self.omega[3]
        a = self.heave_amp
        return a * np.sin(arg), a * w * np.cos(arg), -a * w * w * np.sin(arg)

    def geodetic(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Latitude, longitude (rad) and height (m); straight course (radii at the start)."""
        h, _, _ = self.heave(t)
        r_m, r_n = earth.radii(self.lat0)
        lat = self.lat0 + self.v_course[1] * t / r_m
        lon = self.lon0 + self.v_course[0] * t / (r_n * np.cos(self.lat0))
        return lat, lon, h

    def samples(self, t: np.ndarray, t0_ns: int, dt_ns: int, k0: int = 0) -> list[ShipSample]:
        """Ship samples k0 .. k0+len(t)-1 at times t (s since start); stamps t0_ns + k*dt_ns."""
        t = np.asarray(t, dtype=float)
        e, ed, edd = self.euler(t)
        w_b = euler_rates_to_body_rate(e, ed)
        wdot_b = euler_acc_to_body_acc(e, ed, edd)
        rot = Rotation.from_euler('ZYX', e[:, ::-1])
        q = rot.as_quat()
        h, hd, hdd = self.heave(t)
        v_n = np.tile(self.v_course, (len(t), 1))
        v_n[:, 2] = hd
        a_n = np.zeros_like(v_n)
        a_n[:, 2] = hdd
        c_nb = rot.as_matrix()
        v_b = np.einsum('nji,nj->ni', c_nb, v_n)
        a_b = np.einsum('nji,nj->ni', c_nb, a_n)
        lat, lon, hh = self.geodetic(t)
        p_w = self.plane.from_geodetic(lat, lon, hh)
        return [ShipSample(t_ns=t0_ns + (k0 + i) * dt_ns, p_w=p_w[i], q_nb=q[i], v_b=v_b[i],
                           w_b=w_b[i], a_b=a_b[i], wdot_b=wdot_b[i]) for i in range(len(t))]
