"""The ship's low-frequency track: a straight course at constant speed, or the MMG track of
`course_keeping: mmg` built from the ship configuration."""
from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from alignment_core.geometry import earth
from alignment_core.geometry.euler import heading_to_yaw
from alignment_core.ship.config import ShipConfig
from alignment_core.units import DEG, KNOT

if TYPE_CHECKING:
    from alignment_core.ship.manoeuvring.course_keeping import ManoeuvringTrack, SharedStart

SHARED_CONFIGURATIONS = 4
"""Configurations whose track starts are kept (the latest made): a sweep over many ship
configurations keeps at most this many (some 1.6 MB each, and up to 32 MB of kinematics:
course_keeping.SHARED_KINEMATICS_BYTES)."""
_SHARED: dict[ShipConfig, SharedStart] = {}


def forget_shared_starts() -> None:
    """Drop every shared track start (a benchmark's pass that must start as a fresh process)."""
    _SHARED.clear()


def make_track(cfg: ShipConfig, external=None) -> ManoeuvringTrack:
    """The low-frequency MMG track of `course_keeping: mmg` (course_keeping.ManoeuvringTrack),
    with optional external forces `external(t, north, east, psi) -> (X, Y, N, K)`. Without them,
    the tracks of one configuration share their start (course_keeping.SharedStart): a Monte
    Carlo's runs integrate it once per process."""
    from alignment_core.ship.manoeuvring import mmg
    from alignment_core.ship.manoeuvring.autopilot import Autopilot, CourseSchedule, SteeringGear
    from alignment_core.ship.manoeuvring.course_keeping import ManoeuvringTrack, SharedStart
    shared = None
    if external is None:
        shared = _SHARED.pop(cfg, None) or SharedStart()
        _SHARED[cfg] = shared                           # the latest made last
        while len(_SHARED) > SHARED_CONFIGURATIONS:
            del _SHARED[next(iter(_SHARED))]
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
                            cfg.mmg_step_s, external, shared=shared)


_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)     # 8-point Gauss-Legendre on [-1, 1]


class StraightCourse:
    """Rhumb line at constant ground speed: ENU velocity and yaw constant (heights ignored in
    the radii: heave of metres changes the track by parts in 1e6 of its oscillation)."""

    def __init__(self, lat0: float, lon0: float, heading: float, speed: float) -> None:
        self.lat0, self.lon0, self.speed = lat0, lon0, speed
        self.yaw = heading_to_yaw(heading)
        self.v_n = speed * np.array([np.sin(heading), np.cos(heading), 0.0])

    def _means(self, lat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gauss-Legendre means over [lat0, lat] of R_M and of R_M / (R_N cos lat)."""
        x = 0.5 * (lat[:, None] - self.lat0) * (_GL_X + 1.0) + self.lat0
        r_m, r_n = earth.radii(x)
        w = 0.5 * _GL_W
        return r_m @ w, (r_m / (r_n * np.cos(x))) @ w

    def geodetic(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Latitude and longitude (rad) at times t (s)."""
        t = np.asarray(t, dtype=float)
        s_n = self.v_n[1] * t                                  # northward distance
        r_m0, _ = earth.radii(self.lat0)
        lat = self.lat0 + s_n / r_m0
        for _ in range(4):                                     # Newton on the meridian arc
            m_bar, _ = self._means(lat)
            r_m, _ = earth.radii(lat)
            lat = lat - ((lat - self.lat0) * m_bar - s_n) / r_m
        m_bar, q_bar = self._means(lat)
        lon = self.lon0 + self.v_n[0] * t * q_bar / m_bar
        return lat, lon
