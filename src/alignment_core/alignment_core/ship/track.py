"""The low-frequency MMG track of `course_keeping: mmg`, built from the ship configuration."""
from __future__ import annotations

from dataclasses import replace

from alignment_core.ship.config import ShipConfig
from alignment_core.units import DEG, KNOT


def make_track(cfg: ShipConfig, external=None):
    """The low-frequency MMG track of `course_keeping: mmg` (course_keeping.ManoeuvringTrack),
    with optional external forces `external(t, north, east, psi) -> (X, Y, N, K)`."""
    from alignment_core.ship.manoeuvring import mmg
    from alignment_core.ship.manoeuvring.autopilot import Autopilot, CourseSchedule, SteeringGear
    from alignment_core.ship.manoeuvring.course_keeping import ManoeuvringTrack
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
