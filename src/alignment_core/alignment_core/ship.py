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
from dataclasses import dataclass, replace
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
PAPER_TABLE3_DEG = {3: (1.25, 1.01, 1.03), 4: (2.71, 1.71, 1.92), 5: (5.62, 2.91, 3.36),
                    6: (7.47, 3.15, 4.15), 7: (9.84, 5.27, 6.11)}
# periods (s) roll, pitch, yaw, heave for a 175 m ship (ship-motion.md); 1-2 and 8-9 extend
# its ranges (roll at the natural period, pitch/heave/yaw lengthening with the wave period)
PAPER_PERIOD_S = {1: (17.0, 6.0, 7.5, 6.5), 2: (17.0, 6.25, 7.75, 6.75),
                  3: (17.0, 6.5, 8.0, 7.0), 4: (17.0, 7.0, 8.5, 7.5), 5: (17.0, 7.5, 9.0, 8.0),
                  6: (17.0, 7.75, 9.25, 8.5), 7: (18.5, 8.0, 9.5, 9.0),
                  8: (18.5, 8.5, 10.0, 9.5), 9: (18.5, 9.0, 10.5, 10.0)}
# Bales (1983) mean significant wave height (m) by sea state
BALES_HS_M = {0: 0.0, 1: 0.05, 2: 0.3, 3: 0.88, 4: 1.88, 5: 3.25, 6: 5.0, 7: 7.5, 8: 11.5, 9: 14.0}


def _paper_amplitudes() -> dict[int, tuple[float, float, float]]:
    """Seed 002 Table 3 (sea states 3-7) plus 1-2 and 8-9, which the paper does not give:
    linear response at a fixed period, i.e. amplitude proportional to the Bales Hs, with the
    amplitude per metre of the nearest tabulated sea state (3 for 1-2, 7 for 8-9)."""
    out = dict(PAPER_TABLE3_DEG)
    for ss, ref in ((1, 3), (2, 3), (8, 7), (9, 7)):
        k = BALES_HS_M[ss] / BALES_HS_M[ref]
        out[ss] = tuple(a * k for a in PAPER_TABLE3_DEG[ref])
    return dict(sorted(out.items()))


PAPER_AMPLITUDE_DEG = _paper_amplitudes()


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
    `course_keeping` 'straight' (constant course and speed) or 'mmg': the low-frequency
    track from the MMG manoeuvring model (`mmg.py`, `ship_model` 'carrier' or 'kvlcc2')
    steered by a PID autopilot (`autopilot_kp` rad/rad, `autopilot_ki` 1/s, `autopilot_kd`
    s; rudder `rudder_max_deg`, `rudder_rate_dps`), integrated by RK4 every `mmg_step_s`
    (`course_keeping.py`); the schedule orders `speed_kn` on `heading_deg`, then from
    `turn_at_s` (negative: never) heading `turn_to_deg` (at `turn_rate_dps`, 0 = at once)
    and speed `speed_to_kn` (negative: unchanged); steady wind `wind_speed_kn` from
    `wind_from_deg` (true, from North clockwise). In paper mode the MMG ship also feels
    seed 002's box-ship forces of a regular wave (`box_ship_waves.py`).
    """
    mode: Literal['paper', 'spectral'] = 'spectral'   # the seed scenarios set 'paper' explicitly
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
    course_keeping: Literal['straight', 'mmg'] = 'straight'
    ship_model: Literal['carrier', 'kvlcc2'] = 'carrier'
    autopilot_kp: float = 2.0
    autopilot_ki: float = 0.01
    autopilot_kd: float = 60.0
    rudder_max_deg: float = 35.0
    rudder_rate_dps: float = 2.5
    turn_at_s: float = -1.0
    turn_to_deg: float = 0.0
    turn_rate_dps: float = 0.0
    speed_to_kn: float = -1.0
    wind_speed_kn: float = 0.0
    wind_from_deg: float = 0.0
    mmg_step_s: float = 0.5

    def validate(self) -> None:
        require(0 <= self.sea_state <= 9, f"sea_state must be a WMO code 0-9, got {self.sea_state}")
        if self.mode == 'paper':
            require(self.sea_state in PAPER_AMPLITUDE_DEG or self.sea_state == 0,
                    f"paper mode has amplitudes for sea states 1-9 (seed 002 Table 3, extended) "
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
        require(self.autopilot_kp > 0.0, f"autopilot_kp must be > 0 (rad of rudder per rad of heading "
                                         f"error), got {self.autopilot_kp}")
        require(self.autopilot_ki >= 0.0, f"autopilot_ki must be >= 0 (1/s), got {self.autopilot_ki}")
        require(self.autopilot_kd >= 0.0, f"autopilot_kd must be >= 0 (s), got {self.autopilot_kd}")
        require(0.0 < self.rudder_max_deg <= 45.0,
                f"rudder_max_deg must be in (0, 45], got {self.rudder_max_deg}")
        require(0.0 < self.rudder_rate_dps <= 20.0,
                f"rudder_rate_dps must be in (0, 20], got {self.rudder_rate_dps}")
        require(self.turn_at_s < 0.0 or 0.0 <= self.turn_to_deg <= 360.0,
                f"turn_to_deg must be a heading in [0, 360], got {self.turn_to_deg}")
        require(self.turn_rate_dps >= 0.0,
                f"turn_rate_dps must be >= 0 (0 = ordered at once), got {self.turn_rate_dps}")
        require(self.speed_to_kn < 0.0 or 1.0 <= self.speed_to_kn <= 40.0,
                f"speed_to_kn must be negative (unchanged) or in [1, 40], got {self.speed_to_kn}")
        require(0.0 <= self.wind_speed_kn <= 150.0,
                f"wind_speed_kn must be in [0, 150], got {self.wind_speed_kn}")
        require(-360.0 <= self.wind_from_deg <= 360.0,
                f"wind_from_deg must be in [-360, 360], got {self.wind_from_deg}")
        require(0.01 <= self.mmg_step_s <= 2.0, f"mmg_step_s must be in [0.01, 2] s, got {self.mmg_step_s}")
        if self.course_keeping == 'mmg':
            require(self.speed_kn >= 1.0, f"speed_kn must be >= 1 with course_keeping 'mmg' (the MMG "
                                          f"model is a manoeuvring model at speed), got {self.speed_kn}")
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


def make_track(cfg: ShipConfig, external=None):
    """The low-frequency MMG track of `course_keeping: mmg` (course_keeping.ManoeuvringTrack),
    with optional external forces `external(t, north, east, psi) -> (X, Y, N, K)`."""
    from . import mmg
    from .autopilot import Autopilot, CourseSchedule, SteeringGear
    from .course_keeping import ManoeuvringTrack
    speed = cfg.speed_kn * KNOT
    zeta = cfg.roll_zeta if cfg.roll_zeta > 0.0 else 0.05 + 0.05 * min(speed / (30.0 * KNOT), 1.0)
    ship = replace(mmg.SHIPS[cfg.ship_model], roll_period_s=cfg.roll_period_s, roll_zeta=zeta)
    model = mmg.MmgModel(ship, mmg.Wind(cfg.wind_speed_kn * KNOT, cfg.wind_from_deg * DEG))
    rmax = cfg.rudder_max_deg * DEG
    autopilot = Autopilot(cfg.autopilot_kp, cfg.autopilot_ki, cfg.autopilot_kd, rmax)
    gear = SteeringGear(rmax, cfg.rudder_rate_dps * DEG, gain=min(2.0, 1.0 / cfg.mmg_step_s))
    sched = CourseSchedule(heading0=cfg.heading_deg * DEG, speed0=speed, turn_at=cfg.turn_at_s,
                           turn_to=cfg.turn_to_deg * DEG, turn_rate=cfg.turn_rate_dps * DEG,
                           speed_to=cfg.speed_to_kn * KNOT if cfg.speed_to_kn >= 0.0 else -1.0)
    return ManoeuvringTrack(model, autopilot, gear, sched, cfg.lat_deg * DEG, cfg.lon_deg * DEG,
                            cfg.mmg_step_s, external)


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
        self.track = None
        if cfg.course_keeping == 'mmg':
            self.track = make_track(cfg, self._box_waves(cfg, seed, s))

    @staticmethod
    def _box_waves(cfg: ShipConfig, seed: int, scale: float):
        """Seed 002's regular wave on the box ship (eq 7): height the sea state's mean Hs
        (Bales), period its most probable Tp, travelling `wave_heading_deg` from the initial
        bow; random phase (own stream)."""
        if cfg.sea_state == 0 or scale == 0.0:
            return None
        from . import mmg, sea_state
        from .box_ship_waves import BoxShipWaves
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
        """Ship samples k0 .. k0+len(t)-1 at times t (s since start); stamps t0_ns + k*dt_ns."""
        t = np.asarray(t, dtype=float)
        if self.track is not None:
            return self._samples_mmg(t, t0_ns, dt_ns, k0)
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

    def _samples_mmg(self, t: np.ndarray, t0_ns: int, dt_ns: int, k0: int) -> list[ShipSample]:
        """The paper's sinusoids about the MMG track: yaw and roll of the track added to the
        sinusoids, position and velocity of the track plus heave."""
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
        return [ShipSample(t_ns=t0_ns + (k0 + i) * dt_ns, p_w=p_w[i], q_nb=q[i], v_b=v_b[i],
                           w_b=w_b[i], a_b=a_b[i], wdot_b=wdot_b[i]) for i in range(len(t))]
