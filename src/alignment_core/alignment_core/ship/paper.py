"""Ship six-DOF truth at the master INS point.

Two modes (`ShipConfig.mode`): 'paper' (below) and 'spectral' (`ship/spectral.py`: a random
sea through response amplitude operators on a straight course; see that module).
`make_motion(cfg, seed)` builds either.

Paper mode (seed 002, eq 18): one sinusoid per attitude axis plus heave, on a straight
course at constant speed. Amplitudes are the paper's Table 3 (sea states 3-7); the paper
gives no periods, so roll sits at the natural roll period and pitch, heave and yaw at the
encounter period of a 175 m ship (docs/ship-motion.md); phases are random per axis. Heave
amplitude is half the sea state's mean significant wave height (a regular wave of that
height, heave RAO ~ 1 at these periods).

Truth is INS grade: body rates from Euler rates through the kinematic matrix, angular
acceleration by its exact derivative, and the nav-frame acceleration of the ground velocity.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.geometry import earth
from alignment_core.geometry.euler import euler_acc_to_body_acc, euler_rates_to_body_rate, heading_to_yaw
from alignment_core.rng import stage_rng
from alignment_core.samples import ShipBatch, ShipSample
from alignment_core.ship.config import BALES_HS_M, PAPER_AMPLITUDE_DEG, PAPER_PERIOD_S, ShipConfig
from alignment_core.ship.stamped import split, stamped_batch
from alignment_core.ship.track import make_track
from alignment_core.units import DEG, KNOT
from alignment_core.validation import ConfigError

if TYPE_CHECKING:
    from alignment_core.ship.manoeuvring.course_keeping import ManoeuvringTrack


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
        self.track: ManoeuvringTrack | None = None
        if cfg.course_keeping == 'mmg':
            self.track = make_track(cfg, self._box_waves(cfg, seed, s))

    @staticmethod
    def _box_waves(cfg: ShipConfig, seed: int, scale: float):
        """Seed 002's regular wave on the box ship (eq 7): height the sea state's mean Hs
        (Bales), period its most probable Tp, travelling `wave_heading_deg` from the initial
        bow; random phase (own stream)."""
        if cfg.sea_state == 0 or scale == 0.0:
            return None
        from alignment_core.ship import sea_state
        from alignment_core.ship.manoeuvring import mmg
        from alignment_core.ship.manoeuvring.box_ship_waves import BoxShipWaves
        sea = sea_state.resolve(cfg.sea_state)
        ship = mmg.SHIPS[cfg.ship_model]
        eps = stage_rng(seed, 'ship_box_wave').uniform(0.0, 2.0 * np.pi)
        waves = BoxShipWaves(0.5 * sea.hs_m * scale, 2.0 * np.pi / sea.tp_s,
                             (cfg.heading_deg + cfg.wave_heading_deg) * DEG, eps, ship.lpp,
                             ship.beam, ship.draft, ship.z_h, ship.rho)
        return waves.forces

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
        """`sample_batch` as samples."""
        return split(self.sample_batch(t, t0_ns, dt_ns, k0))

    def sample_batch(self, t: np.ndarray, t0_ns: int, dt_ns: int, k0: int = 0) -> ShipBatch:
        """Ship samples k0 .. k0+len(t)-1 at times t (s since start), stamps t0_ns + k*dt_ns."""
        t = np.asarray(t, dtype=float)
        if self.track is not None:
            return self._batch_mmg(t, t0_ns, dt_ns, k0)
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
        return stamped_batch(t0_ns, dt_ns, k0, p_w, q, v_b, w_b, a_b, wdot_b)

    def _batch_mmg(self, t: np.ndarray, t0_ns: int, dt_ns: int, k0: int) -> ShipBatch:
        """The paper's sinusoids about the MMG track: yaw and roll of the track added to the
        sinusoids, position and velocity of the track plus heave."""
        assert self.track is not None                   # course_keeping 'mmg'
        lf = self.track.kinematics(t)
        e, ed, edd = self.euler(t)
        e[:, 2] += heading_to_yaw(lf['psi']) - self.yaw0
        ed[:, 2] -= lf['psi_dot']
        edd[:, 2] -= lf['psi_ddot']
        e[:, 0] += lf['phi']
        ed[:, 0] += lf['phi_dot']
        edd[:, 0] += lf['phi_ddot']
        w_b = euler_rates_to_body_rate(e, ed)
        wdot_b = euler_acc_to_body_acc(e, ed, edd)
        rot = Rotation.from_euler('ZYX', e[:, ::-1])
        q = rot.as_quat()
        h, hd, hdd = self.heave(t)
        v_n = lf['v_n'].copy()
        a_n = lf['a_n'].copy()
        v_n[:, 2] += hd
        a_n[:, 2] += hdd
        c_nb = rot.as_matrix()
        v_b = np.einsum('nji,nj->ni', c_nb, v_n)
        a_b = np.einsum('nji,nj->ni', c_nb, a_n)
        p_w = self.plane.from_geodetic(lf['lat'], lf['lon'], h)
        return stamped_batch(t0_ns, dt_ns, k0, p_w, q, v_b, w_b, a_b, wdot_b)
